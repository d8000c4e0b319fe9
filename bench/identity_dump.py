"""Every number the engine gives on the real models of tests/data, as one dict of arrays.

    python bench/identity_dump.py OUT.npz           # dump this build
    python bench/compare_builds.py OTHER --identity  # dump both builds, compare bit for bit

For a restructuring that must not change any result (one build against another): each model
of tests/data is analysed with outlines kept, junctions on and off, at two intervals, with a
minimum thickness that flags thin sections (the thickness code) and once live (an
``Analyzer`` run twice, the second time with moved vertices: the reuse paths). The cow with a
far copy and an inner copy of a small model added exercises the loose-piece finder (one piece
loose, one attached); ``correct`` runs on the cow and RigNet 2982; the cow subdivided once
(~93k faces) is analysed once; ``slice_section`` cuts the cow on a few
planes. Arrays are compared byte for byte after a dtype and shape check: a NaN must sit at the
same place and every other bit must match.
"""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
DATA = HERE.parent / "tests" / "data"

#: (name, mesh, skeleton, weights); None: the loader finds the file next to the mesh
MODELS = [
    *[(f"rignet{n}", f"RigNet/{n}_ori.obj", None, None)
      for n in (11814, 1347, 15446, 17872, 2586, 2982, 8184, 8333)],
    ("fox", "glTF-Sample-Models/Fox.glb", None, None),
    ("cow", "Hyperspectral-Inverse-Skinning/cow_clean.obj", "Hyperspectral-Inverse-Skinning/cow.tgf",
     "Hyperspectral-Inverse-Skinning/cow.DMAT"),
    ("cheburashka", "Hyperspectral-Inverse-Skinning/cheburashka.obj", None, None),
    ("wolf", "Hyperspectral-Inverse-Skinning/wolf_clean.obj",
     "Hyperspectral-Inverse-Skinning/wolf.tgf", "Hyperspectral-Inverse-Skinning/wolf.DMAT"),
    ("cylinder", "Hyperspectral-Inverse-Skinning/cylinder.obj", None, None),
    ("arm", "libigl-tutorial-data/arm.obj", None, None),
    ("elephant", "libigl-tutorial-data/elephant.obj", None, None),
]


def _load(mesh, skeleton, weights):
    from osteon.io import load_model

    m = load_model(DATA / mesh, skeleton=skeleton and DATA / skeleton,
                   weights=weights and DATA / weights)
    return np.asarray(m.vertices, float), np.asarray(m.faces, np.int32), m.skeleton, m.weights


def _flatten(prefix: str, value, out: dict) -> None:
    """value's numbers into out under prefix (dataclasses field by field, lists of arrays
    concatenated with their lengths)."""
    if dataclasses.is_dataclass(value):
        for f in dataclasses.fields(value):
            if f.name != "thickness_pending":
                _flatten(f"{prefix}.{f.name}", getattr(value, f.name), out)
    elif isinstance(value, dict):
        for k, v in value.items():
            _flatten(f"{prefix}.{k}", v, out)
    elif isinstance(value, (list, tuple)) and value and all(
            isinstance(v, np.ndarray) for v in value):
        out[prefix + ".lengths"] = np.array([len(v) for v in value])
        out[prefix] = np.concatenate([np.asarray(v).ravel() for v in value])
    elif isinstance(value, str):
        out[prefix] = np.array(value)
    elif value is not None:
        out[prefix] = np.asarray(value)


def _with_shells(v, f, w, extra_v, extra_f):
    """The mesh with two copies of a small model added: one far outside (loose) and one inside
    near the centre (attached); each copy bound to the first bone."""
    from scipy import sparse

    lo, hi = v.min(0), v.max(0)
    size = extra_v.max(0) - extra_v.min(0)
    small = (extra_v - extra_v.min(0)) * (0.1 * (hi - lo).max() / size.max())
    far = small + hi + 0.5 * (hi - lo)
    inner = small - small.mean(0) + v.mean(0)
    nv = len(v)
    vv = np.concatenate([v, far, inner])
    ff = np.concatenate([f, extra_f + nv, extra_f + nv + len(small)]).astype(np.int32)
    w = sparse.csr_matrix(w) if w is not None else None
    if w is not None:
        add = sparse.csr_matrix((np.ones(2 * len(small)), (np.arange(2 * len(small)),
                                                           np.zeros(2 * len(small), int))),
                                shape=(2 * len(small), w.shape[1]))
        w = sparse.vstack([w, add]).tocsr()
    return vv, ff, w


def dump() -> dict:
    """Every number of the analyses described in the module docstring, by name."""
    import osteon

    out: dict = {}
    loaded = {name: _load(*paths) for name, *paths in MODELS}
    for name, (v, f, sk, w) in loaded.items():
        for h in (2.0, 5.0):
            for junctions in (True, False):
                a = osteon.analyze(v, f, sk, w, interval=h, threads=1, keep_outlines=True,
                                   junctions=junctions, min_thickness=1.5)
                _flatten(f"{name}.h{h:g}.j{int(junctions)}", a, out)
        a = osteon.analyze(v, f, sk, w, threads=2, local_cuts=False, keep_outlines=True)
        _flatten(f"{name}.whole_planes", a, out)
        live = osteon.Analyzer(f, len(v), sk, w, threads=1, keep_outlines=True)
        _flatten(f"{name}.live0", live.run(v), out)
        moved = v + 0.01 * np.sin(v[:, [1, 2, 0]])
        _flatten(f"{name}.live1", live.run(moved), out)
    cv, cf, csk, cw = loaded["cow"]
    ev, ef = loaded["cylinder"][:2]
    sv, sf, sw = _with_shells(cv, cf, cw, ev, ef)
    for gap in (None, 0.0, 2.0):
        a = osteon.analyze(sv, sf, csk, sw, threads=1, keep_outlines=True, gap_tolerance=gap)
        _flatten(f"cow_shells.gap{gap}", a, out)
    live = osteon.Analyzer(sf, len(sv), csk, sw, threads=1)
    _flatten("cow_shells.live0", live.run(sv), out)
    _flatten("cow_shells.live1", live.run(sv * 1.01), out)
    for name in ("cow", "rignet2982"):  # both take ~20 rounds; the cow's ends unconverged
        _flatten(f"{name}.correct", osteon.correct(*loaded[name], allowable_stress=20.0,
                                                   threads=1), out)
    from models import subdivide

    big_v, big_f, big_w = subdivide(cv, cf, cw)  # ~93k faces: the grids' larger paths
    _flatten("cow_x4", osteon.analyze(big_v, big_f, csk, big_w, threads=1, keep_outlines=True),
             out)
    centre = cv.mean(0)
    for i, normal in enumerate(((1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 0.3))):
        _flatten(f"cow.slice{i}", osteon.slice_section(cv, cf, centre, normal), out)
    return out


def compare(a: dict, b: dict) -> list[str]:
    """The names whose arrays differ: missing in one, other dtype or shape, or any bit (so a NaN
    must sit at the same place, and -0.0 is not 0.0)."""
    bad = sorted(set(a) ^ set(b))
    for k in sorted(set(a) & set(b)):
        x, y = np.asarray(a[k]), np.asarray(b[k])
        if x.dtype != y.dtype or x.shape != y.shape or x.tobytes() != y.tobytes():
            bad.append(k)
    return bad


def array_kind(name: str) -> str:
    """The result field a dump name holds (its last part; a list's lengths keep their field)."""
    parts = name.split(".")
    return ".".join(parts[-2:]) if parts[-1] == "lengths" and len(parts) > 1 else parts[-1]


def largest_relative(a: dict, b: dict, names: list[str]) -> dict:
    """Per array kind (array_kind) of the differing `names`: (largest relative difference, the
    name it is in). Relative to the larger magnitude of the two numbers (denormal floor); NaN
    against a number, another shape or dtype, a missing array or any integer, boolean or text
    difference counts as inf (a different section, flag or count, not rounding)."""
    worst: dict = {}
    for k in names:
        rel = float("inf")
        if k in a and k in b:
            x, y = np.asarray(a[k]), np.asarray(b[k])
            if x.shape == y.shape and x.dtype == y.dtype and np.issubdtype(x.dtype, np.floating):
                xf, yf = x.astype(np.float64).ravel(), y.astype(np.float64).ravel()
                same_nan = np.array_equal(np.isnan(xf), np.isnan(yf))
                ok = ~np.isnan(xf)
                if same_nan and np.array_equal(np.isinf(xf), np.isinf(yf)) and \
                        np.array_equal(xf[np.isinf(xf)], yf[np.isinf(yf)]):
                    ok &= np.isfinite(xf)
                    scale = np.maximum(np.maximum(np.abs(xf[ok]), np.abs(yf[ok])), 1e-300)
                    rel = float((np.abs(xf[ok] - yf[ok]) / scale).max(initial=0.0))
        kind = array_kind(k)
        if kind not in worst or rel > worst[kind][0]:
            worst[kind] = (rel, k)
    return worst


if __name__ == "__main__":
    np.savez(sys.argv[1], **dump())
