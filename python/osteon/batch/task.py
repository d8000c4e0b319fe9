"""The per-model task of a batch: read, check, analyse (and correct), report, picture.

:func:`process_model` takes a path, never a loaded model, so a task carries a few hundred
bytes to a worker and the memory of a run is bounded by the models in flight. It never raises:
every problem becomes ``status`` + ``reason`` in the returned record. It writes no file either:
the picture and the corrected mesh come back as bytes in ``record["_files"]`` and the caller
(the process that owns ``--out``) writes them, so Dask workers need to read the inputs but
not to share the output folder.

Units: mm, N, MPa.
"""

from __future__ import annotations

import io
import time
from pathlib import Path

import numpy as np

from ..settings import SECTION_LIMIT, min_thickness_mm, section_budget
from .settings import BatchSettings

#: ``status`` values: analysed; not analysed because the model has no skeleton (and no automatic
#: skeleton is available); not analysed because the file is bad (unreadable, open, rejected by
#: the engine).
STATUSES = ("ok", "skipped", "failed")
NO_SKELETON = "no skeleton (auto_skeleton not available)"

# keys of the full report that stay out of results.jsonl (they are in the per-model JSON)
BULKY_KEYS = ("section_table", "bones", "bone_results", "bone_names", "correction",
              "bone_scale", "bone_scale_xz")


class _Skip(Exception):
    pass


def mesh_boundary(faces: np.ndarray, n_vertices: int) -> tuple[int, int]:
    """(boundary edges, non-manifold edges) of a triangle mesh: edges used by one face, and by
    more than two. A closed (watertight) surface has neither of the first."""
    f = np.asarray(faces)
    a, b = f.ravel(), f[:, [1, 2, 0]].ravel()  # the edges (f0, f1), (f1, f2), (f2, f0)
    # one int64 code per undirected edge (min/max, not a row sort: 3x faster)
    code = np.minimum(a, b).astype(np.int64) * np.int64(n_vertices) + np.maximum(a, b)
    code.sort()
    new = np.empty(len(code) + 1, dtype=bool)  # where a run of equal codes starts, and the end
    new[0] = new[-1] = True
    np.not_equal(code[1:], code[:-1], out=new[1:-1])
    counts = np.diff(np.flatnonzero(new))
    return int(np.count_nonzero(counts == 1)), int(np.count_nonzero(counts > 2))


def welded_faces(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, faces) with vertices at the same position merged (STL stores every triangle's
    corners apart, so its topology only shows once they are merged)."""
    uniq, inverse = np.unique(np.asarray(vertices), axis=0, return_inverse=True)
    return uniq, inverse.ravel()[np.asarray(faces)].astype(np.int32)


def _is_unrigged(path: Path) -> bool:
    """True when a mesh file has no skeleton next to it (load_model would refuse it)."""
    from ..io.loader import MESH_EXTENSIONS, _sidecar

    return path.suffix.lower() in MESH_EXTENSIONS and _sidecar(path, [".tgf", "_rig.txt"]) is None


def _auto_rigged(path: Path, s: BatchSettings):
    """An unrigged mesh read and given ``osteon.auto_skeleton`` (issue 17) when it exists."""
    import osteon

    from ..io import RiggedModel, read_mesh

    if path.suffix.lower() in (".gltf", ".glb"):
        import trimesh

        m = trimesh.load(str(path), force="mesh", process=False)
        V, F = np.asarray(m.vertices, float), np.asarray(m.faces, np.int32)
    else:
        V, F = read_mesh(path)  # read first: a file that is not a mesh is "unreadable"
    if not hasattr(osteon, "auto_skeleton"):
        raise _Skip(NO_SKELETON)
    V, F = welded_faces(V, F)  # no weights to keep in line: the skeleton needs the topology
    height, axis = s.height_and_axis()
    ext = V.max(0) - V.min(0)
    size = float(ext.max() if axis is None else ext["xyz".index(axis)])
    if height is not None:
        if size <= 0:
            raise ValueError("mesh has zero size; cannot scale it")
        V = V * (height / size)
    sk, W = osteon.auto_skeleton(V, F, min_thickness=min_thickness_mm(s.settings))
    names = list(getattr(sk, "names", None) or [f"bone_{i}" for i in range(len(sk.parents))])
    return RiggedModel(
        V, F, sk.heads, sk.tails, sk.parents, names, W, source=str(path), notes=["auto skeleton"]
    )


def _load(path: Path, s: BatchSettings):
    from ..io import load_model

    if _is_unrigged(path):
        return _auto_rigged(path, s)
    height, axis = s.height_and_axis()
    try:
        return load_model(path, height_mm=height, axis=axis)
    except ValueError as e:
        if "has no skin" in str(e):  # a glTF without a skeleton
            return _auto_rigged(path, s)
        raise


def _report(path, model, s: BatchSettings, analysis, seconds, fix=None):
    """The per-model report: the one schema of :func:`osteon.report.build_report`."""
    from ..report import build_report

    settings = s.settings.as_dict()
    settings["correct"] = s.correct
    return build_report(
        analysis=analysis if fix is None else fix.before, bone_names=model.bone_names,
        allowable_mpa=s.allowable_mpa, settings=settings, front_end="batch", model=str(path),
        mm_per_unit=model.scale, vertices=len(model.vertices), faces=len(model.faces),
        seconds=seconds, correction=fix,
    )


def _section_flag_counts(analysis) -> dict[str, int]:
    import osteon

    flags = np.asarray(analysis.section_flags)
    return {
        name: int(np.count_nonzero(flags & bit))
        for name, bit in osteon.SECTION_FLAGS.items()
        if np.any(flags & bit)
    }


def _png_bytes(model, analysis, allowable, s: BatchSettings, title, vertices=None):
    """The contact-sheet picture (``osteon.plots.save_stress_thumbnail``) as PNG bytes."""
    from ..plots import save_stress_thumbnail

    buf = io.BytesIO()
    save_stress_thumbnail(
        buf, model.vertices if vertices is None else vertices, model.faces, analysis, allowable,
        title=title, dpi=s.png_dpi,
    )
    return buf.getvalue()


def process_model(path: str, settings, model_id: str | None = None) -> dict:
    """Analyse one model file; never raises. Returns the record of the model:

    ``model`` (path), ``id``, ``status`` (``ok`` / ``skipped`` / ``failed``), ``reason`` (why
    not ok, else None), ``seconds`` (whole task) and ``read_seconds``, ``check_seconds``,
    ``analysis_seconds``, ``png_seconds``; when analysed also the report's fields
    (:func:`osteon.report.build_report`: ``faces``, ``vertices``, ``max_stress_mpa``,
    ``stress_ratio``, ``allowable_stress_mpa``, ``weak_bones``, ``bones``, ``section_table``,
    …) plus ``bone_count`` and ``flags`` (what to look at: section flags with counts,
    ``open mesh:N``, ``non-manifold edges:N``, ``nearest-bone weights``, ``auto skeleton``,
    ``not converged``). ``_files`` maps output names (``ID.png``, ``ID_corrected.EXT``) to
    bytes for the caller to write.
    """
    t0 = time.perf_counter()
    p = Path(path)
    rec: dict = {"model": str(path), "id": model_id or p.stem, "status": "ok", "reason": None}
    times = {"read_seconds": 0.0, "check_seconds": 0.0, "analysis_seconds": 0.0,
             "png_seconds": 0.0}
    files: dict[str, bytes] = {}
    try:
        import osteon

        s = BatchSettings.from_any(settings)
        allowable = s.allowable_mpa
        t = time.perf_counter()
        try:
            model = _load(p, s)
        except _Skip:
            raise
        except ValueError as e:
            raise ValueError(f"unreadable: {_one_line(e)}") from None
        except Exception as e:  # noqa: BLE001 - any reader failure is a bad file
            raise ValueError(f"unreadable: {type(e).__name__}: {_one_line(e)}") from None
        times["read_seconds"] = time.perf_counter() - t
        t = time.perf_counter()
        flags: list[str] = []
        if "auto skeleton" in model.notes:
            flags.append("auto skeleton")
        if model.weights is None:
            flags.append("nearest-bone weights")
        if model.warnings:
            flags.append(f"warnings:{len(model.warnings)}")
        boundary, nonmanifold = mesh_boundary(model.faces, len(model.vertices))
        if boundary:  # corners stored apart (STL)? the topology of the merged positions counts
            Vw, Fw = welded_faces(model.vertices, model.faces)
            boundary, nonmanifold = mesh_boundary(Fw, len(Vw))
        times["check_seconds"] = time.perf_counter() - t
        if boundary:
            if not s.allow_open:
                raise ValueError(
                    f"open mesh: {boundary} boundary edges (a print needs a closed surface; "
                    "allow_open / --allow-open analyses it anyway)"
                )
            flags.append(f"open mesh:{boundary}")
        if nonmanifold:
            flags.append(f"non-manifold edges:{nonmanifold}")
        engine = s.engine_kwargs(model.bone_names)
        positional = (model.vertices, model.faces, model.skeleton, model.weights)
        n_sections = osteon.estimate_sections(model.skeleton, engine["interval"])
        ext_mm = model.vertices.max(0) - model.vertices.min(0)
        over = section_budget(n_sections, len(model.vertices), engine["interval"],
                              float(ext_mm.max()), s.max_sections)
        if over:  # refused before the work: a scale or setting that would run for minutes
            raise ValueError(f"refused: {over}")
        if n_sections > SECTION_LIMIT:  # a setting or scale that makes this model slow
            flags.append(f"many sections:{n_sections}")
        t = time.perf_counter()
        fix = None
        if s.correct:
            fix = osteon.correct(*positional, **engine)
            analysis = fix.after
        else:
            analysis = osteon.analyze(*positional, **engine)
        times["analysis_seconds"] = time.perf_counter() - t
        from ..cli.common import check_overflow

        check_overflow(analysis if fix is None else fix.before, engine["force"])
        rep = _report(path, model, s, analysis, times["analysis_seconds"], fix)
        rep["bone_count"] = len(model.bone_names)
        for name, n in _section_flag_counts(analysis).items():
            flags.append(f"{name}:{n}")
        if fix is not None:
            if not fix.converged:
                flags.append("not converged")
            ext = p.suffix.lower() if p.suffix.lower() in (".obj", ".off", ".ply", ".stl") else ".obj"
            from ..io import write_mesh

            tmp = io.BytesIO()
            _write_mesh_bytes(write_mesh, tmp, fix.vertices, model.faces, ext)
            files[f"{rec['id']}_corrected{ext}"] = tmp.getvalue()
            rep["output"] = f"{rec['id']}_corrected{ext}"
        if s.slicer_project:
            files.update(_slicer_project(rec["id"], model, s, engine, rep))
        rec.update(rep)
        rec["flags"] = flags
        rec["warnings"] = [*rec.get("warnings", []), *model.warnings]  # the report's + reader's
        if s.png:
            t = time.perf_counter()
            material = s.settings.material_and_strength()[0]
            title = (f"{p.name}: F = {s.settings.force_n:g} N, {material} "
                     f"[σ] = {allowable:g} MPa")
            files[f"{rec['id']}.png"] = _png_bytes(
                model, analysis, allowable, s, title,
                vertices=None if fix is None else fix.vertices,
            )
            times["png_seconds"] = time.perf_counter() - t
            rec["png"] = f"{rec['id']}.png"
    except _Skip as e:
        rec.update(status="skipped", reason=str(e))
    except Exception as e:  # noqa: BLE001 - one bad model must not stop the batch
        msg = _one_line(e)
        rec.update(status="failed", reason=msg if isinstance(e, ValueError) else
                   f"{type(e).__name__}: {msg}")
    rec.update(times)
    rec["seconds"] = time.perf_counter() - t0
    rec["_files"] = files
    return rec


def _slicer_project(model_id: str, model, s: BatchSettings, engine: dict, rep: dict) -> dict:
    """Reinforce the model under the settings' print profile (:func:`osteon.reinforce`); the
    report's ``reinforcement`` and ``{ID.3mf: bytes}`` (the slicer project)."""
    import os
    import tempfile

    import osteon

    from ..report import reinforcement_section

    kw = {k: v for k, v in engine.items() if k not in ("max_scale", "max_rounds", "scaling")}
    profile = kw.pop("print_profile", None)
    if profile is None:
        profile = s.settings.profile() if hasattr(s.settings, "profile") else None
    if profile is None or profile.kind != "fdm":
        raise ValueError("slicer_project needs an FDM print profile (walls and infill)")
    r = osteon.reinforce(model.vertices, model.faces, model.skeleton, model.weights,
                         print_profile=profile, **kw)
    name = f"{model_id}.3mf"
    fd, tmp = tempfile.mkstemp(suffix=".3mf")
    os.close(fd)
    try:
        r.write_3mf(tmp, slicer=s.slicer_project, name=model_id)
        data = Path(tmp).read_bytes()
    finally:
        os.unlink(tmp)
    rep["reinforcement"] = reinforcement_section(r, s.slicer_project, name)
    return {name: data}


def _write_mesh_bytes(write_mesh, buf, vertices, faces, ext):
    import os
    import tempfile

    fd, name = tempfile.mkstemp(suffix=ext)
    os.close(fd)
    try:
        write_mesh(name, vertices, faces)
        buf.write(Path(name).read_bytes())
    finally:
        os.unlink(name)


def _one_line(e) -> str:
    text = str(e).strip()
    return text.splitlines()[0] if text else type(e).__name__


def summary_line(record: dict) -> dict:
    """The record without its bulky tables and file bytes: one line of ``results.jsonl``."""
    return {k: v for k, v in record.items() if k not in BULKY_KEYS and k != "_files"}
