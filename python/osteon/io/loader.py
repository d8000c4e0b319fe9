"""Mesh reading/writing (trimesh) and :func:`load_model`, the one-call reader."""

from __future__ import annotations

import functools
import io
import os
from pathlib import Path

import numpy as np

from .atomic import write_atomic
from .libigl import read_dmat, read_tgf
from .model import RiggedModel, dense_weights

MESH_EXTENSIONS = (".obj", ".off", ".ply", ".stl")
GLTF_EXTENSIONS = (".gltf", ".glb")


def _exists(path, what):
    p = Path(os.fspath(path))
    if not p.is_file():
        raise ValueError(f"{what} not found: {p}")
    return p


def read_mesh(path):
    """Read a triangle mesh (OBJ/OFF/PLY/STL) → ``(vertices (V,3) float64, faces (F,3) int32)``.

    The file's vertex order is kept (no merging or reordering) so that skinning weights given
    per vertex still line up; polygons are triangulated by trimesh.
    """
    p = _exists(path, "mesh file")
    ext = p.suffix.lower()
    if ext not in MESH_EXTENSIONS:
        raise ValueError(
            f"{p}: unknown mesh format {ext!r}; supported: "
            + ", ".join(MESH_EXTENSIONS + GLTF_EXTENSIONS)
        )
    try:
        with open(p, "rb") as fh:
            raw = fh.read()
    except OSError as e:
        raise ValueError(f"{p}: cannot read ({e.strerror or e})") from None
    from .fastmesh import parse_mesh

    fast = parse_mesh(raw, ext, str(p))
    if fast is not None:
        return fast
    try:
        import trimesh
    except ModuleNotFoundError:
        raise ValueError(f"{p}: reading {ext} meshes needs the Python package 'trimesh' "
                         "(pip install trimesh)") from None
    try:
        # the bytes, not the name: any file name, UTF-8 or not
        m = trimesh.load(io.BytesIO(raw), file_type=ext[1:], process=False,
                         maintain_order=True, force="mesh")
    except ModuleNotFoundError as e:  # an optional package of one trimesh loader
        raise ValueError(f"{p}: reading {ext} meshes needs the Python package {e.name!r} "
                         f"(pip install {e.name})") from None
    except Exception as e:  # noqa: BLE001 - trimesh loaders raise many kinds
        raise ValueError(f"{p}: cannot read mesh ({_plain(e)})") from None
    if not isinstance(m, trimesh.Trimesh) or len(m.faces) == 0:
        raise ValueError(f"{p}: no triangles found in the mesh file")
    return np.asarray(m.vertices, dtype=np.float64), np.asarray(m.faces, dtype=np.int32)


def plain_words(text: str) -> str:
    """A third-party error message in plain words where it is one of the known cryptic ones
    (NumPy's reshape, LinAlg's singular matrix, a Qhull code), else the message itself."""
    low = text.lower()
    if "cannot reshape array" in low:
        return "the numbers do not fill whole rows (a truncated or malformed file)"
    if "singular matrix" in low:
        return "a transform that cannot be inverted (singular matrix)"
    if text.startswith("QH") or "qhull" in low:
        return "the points are flat or degenerate (convex hull failed)"
    return text


def _plain(e: Exception) -> str:
    """An exception of a third-party reader in plain words, one line."""
    text = str(e).strip().splitlines()[0] if str(e).strip() else ""
    plain = plain_words(text)
    if plain != text:
        return plain
    return f"{type(e).__name__}: {text}" if text else type(e).__name__


def write_mesh(path, vertices, faces):
    """Write a triangle mesh; the format follows the extension (OBJ/OFF/PLY/STL)."""
    import trimesh

    ext = Path(path).suffix.lower()
    if ext not in MESH_EXTENSIONS:
        raise ValueError(f"{path}: cannot write mesh format {ext!r}; use one of {MESH_EXTENSIONS}")
    m = trimesh.Trimesh(np.asarray(vertices), np.asarray(faces), process=False)
    write_atomic(path, writer=lambda tmp: m.export(tmp, file_type=ext[1:]))


def _sidecar(mesh: Path, suffixes):
    """The first file next to ``mesh`` named its stem + one of ``suffixes``, in any letter
    case (``arm.TGF``); None when there is none. Exact names are looked up first (a stat
    each); the folder is listed only when none exists, and that listing is kept while the
    folder is unchanged, so a batch over a flat folder of N models lists it once, not N times
    (N² names)."""
    stem = mesh.with_suffix("")
    folder = mesh.parent
    for s in suffixes:
        exact = folder / (stem.name + s)
        if exact.is_file():
            return exact
    names = _names_in(folder)
    for s in suffixes:
        cand = names.get((stem.name + s).lower())
        if cand is not None and cand.is_file():  # a stale listing names no file
            return cand
    return None


def _names_in(folder: Path) -> dict:
    """{lower-case name: path} of the files in ``folder`` ({} if it is not one), listed once per
    state of the folder (its modification time)."""
    try:
        stamp = os.stat(folder).st_mtime_ns
    except OSError:
        return {}
    return _listing(str(folder), stamp)


@functools.lru_cache(maxsize=16)
def _listing(folder: str, stamp: int) -> dict:
    try:
        return {f.name.lower(): f for f in Path(folder).iterdir()}
    except OSError:
        return {}


def load_model(
    path, skeleton=None, weights=None, height_mm: float | None = 120.0, axis=None
) -> RiggedModel:
    """Read a rigged model and scale it to a printed size in millimetres.

    Parameters
    ----------
    path : mesh file (OBJ/OFF/PLY/STL) or skinned glTF (.gltf/.glb).
    skeleton : TGF or RigNet ``_rig.txt`` file. If omitted for a mesh file, ``NAME.tgf`` or
        ``NAME_rig.txt`` next to the mesh is used.
    weights : DMAT file (columns = TGF bones). If omitted with a TGF skeleton, ``NAME.dmat``,
        ``NAME-weights.dmat`` or ``NAME_weights.dmat`` next to the mesh is used; without any
        weights the model has ``weights=None`` (osteon then binds each vertex to its nearest bone).
    height_mm : printed size in mm of the model's largest bounding-box extent (or of its extent
        along ``axis``: 'x', 'y' or 'z'); ``None`` keeps the file's units.

    Every problem of the files is a ValueError naming the file and what is wrong (missing files,
    unknown formats, bad indices, cycles, weights that do not match); repaired weights and bones
    without weight are listed in the model's ``warnings``.
    """
    try:
        return _load_model(path, skeleton, weights, height_mm, axis)
    except (ValueError, MemoryError, KeyboardInterrupt):
        raise
    except RecursionError:
        raise ValueError(f"{os.fspath(path)}: the file nests too deeply to read") from None
    except OSError as e:  # unreadable, a folder, a symlink loop
        raise ValueError(f"{e.filename or os.fspath(path)}: cannot read "
                         f"({e.strerror or type(e).__name__})") from None
    except Exception as e:  # noqa: BLE001 - a malformed file that a check above missed
        text = str(e).strip().splitlines()[0] if str(e).strip() else ""
        raise ValueError(f"{os.fspath(path)}: malformed file ({type(e).__name__}"
                         f"{': ' + text if text else ''})") from None


def _load_model(path, skeleton, weights, height_mm, axis) -> RiggedModel:
    p = _exists(path, "model file")
    ext = p.suffix.lower()
    notes = []
    if ext in GLTF_EXTENSIONS:
        if skeleton is not None or weights is not None:
            raise ValueError(
                f"{p}: a glTF file carries its own skin; do not pass a skeleton or weights file"
            )
        from .gltf import read_gltf

        info = {"notes": notes}
        V, F, heads, tails, parents, names, W = read_gltf(p, info)
        m = RiggedModel(V, F, heads, tails, parents, names, W, source=str(p), notes=notes,
                        warnings=info["warnings"], weight_findings=info.get("findings", {}))
        return m.scaled_to(height_mm, axis)
    V, F = read_mesh(p)
    if skeleton is None:
        skeleton = _sidecar(p, [".tgf", "_rig.txt"])
        if skeleton is None:
            raise ValueError(
                f"{p}: no skeleton given and no {p.stem}.tgf or {p.stem}_rig.txt next to it; "
                "pass a skeleton file (TGF or RigNet _rig.txt)"
            )
        notes.append(f"skeleton: {skeleton}")
    sk = _exists(skeleton, "skeleton file")
    info = {"notes": notes, "warnings": []}
    sname = sk.name.lower()
    if sname.endswith(".tgf"):
        _, _, heads, tails, parents = read_tgf(sk)
        names = [f"bone_{i}" for i in range(len(parents))]
        W = None
        if weights is None:
            weights = _sidecar(p, [".dmat", "-weights.dmat", "_weights.dmat"])
            if weights is not None:
                notes.append(f"weights: {weights}")
        if weights is not None:
            wp = _exists(weights, "weights file")
            if not wp.name.lower().endswith(".dmat"):
                raise ValueError(f"{wp}: weights must be a DMAT file")
            Wd = read_dmat(wp)
            if Wd.shape != (len(V), len(parents)):
                raise ValueError(
                    f"{wp}: weights are {Wd.shape[0]} rows x {Wd.shape[1]} columns but the mesh "
                    f"has {len(V)} vertices and the skeleton {len(parents)} bones"
                )
            W, info["findings"], warns = dense_weights(Wd, str(wp), names)
            info["warnings"].extend(warns)
    elif sname.endswith(".txt"):
        if weights is not None:
            raise ValueError(
                f"{sk}: a RigNet rig carries its own skin weights; do not pass a weights file"
            )
        from .rignet import read_rignet_rig, rignet_skeleton

        rig = read_rignet_rig(sk)
        heads, tails, parents, names, W = rignet_skeleton(rig, V, info, str(sk))
    else:
        raise ValueError(f"{sk}: unknown skeleton format; use a .tgf or a RigNet _rig.txt file")
    m = RiggedModel(V, F, heads, tails, parents, names, W, source=str(p), notes=notes,
                    warnings=info["warnings"], weight_findings=info.get("findings", {}))
    return m.scaled_to(height_mm, axis)
