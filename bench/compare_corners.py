"""The corners this build finds against another build's, bit for bit (issue 33's cost work).

    python bench/compare_corners.py OTHER_PYTHONPATH [--keep DIR]

Every corner field (``notch``, ``stress_concentration``, ``notch_radius``, ``notch_step``,
``stress``) of: the 16 models of bench/identity_dump.py (its 15 real models of tests/data and the
cow subdivided once, ~93k faces), each scaled to a 120 mm print, at h = 2 and 8 mm, with
``min_notch_radius`` 0.2 (FDM) and 0.01 mm (the measured radius, nearly unclamped), with 1 and
2 threads; and the stepped bars of tests/python/test_notch.py (fillets 1.2 ... 0.06 mm, a sharp
step, a cone). One child process per build (two pybind11 builds cannot share one); arrays
compared byte for byte. Also checks, in each build, that 1 and 2 threads give the same bytes.
Prints the sections with a corner per build and every difference (model, h, section: Kt,
radius, D/d before and after). Exits 1 on any difference.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from compare_builds import OTHER_BUILD_IMPORT, both_dumps, other_build_args

CHILD = OTHER_BUILD_IMPORT + """sys.path.insert(0, {tests!r})
import numpy as np, osteon, compare_corners
np.savez({out!r}, **compare_corners.dump())
print(osteon.__file__)
"""

FIELDS = ("notch", "stress_concentration", "notch_radius", "notch_step", "stress")


def _models():
    """(name, vertices, faces, skeleton, weights) of the 16 models, 120 mm tall."""
    import osteon
    from identity_dump import DATA, MODELS
    from osteon.io import load_model
    from rigged_models import subdivide

    for name, mesh, skel, weights in MODELS:
        m = load_model(DATA / mesh, skeleton=skel and DATA / skel,
                       weights=weights and DATA / weights, height_mm=120.0)
        v, f = np.asarray(m.vertices, float), np.asarray(m.faces, np.int32)
        sk = m.skeleton if isinstance(m.skeleton, osteon.Skeleton) else osteon.Skeleton(
            m.heads, m.tails, m.parents, m.bone_names)
        yield name, v, f, sk, m.weights
        if name == "cow":
            bv, bf, bw = subdivide(v, f, m.weights)
            yield "cow_x4", bv, bf, sk, bw


def dump() -> dict:
    import osteon
    from test_notch import bar_skeleton, stepped_bar

    out: dict = {}
    for name, v, f, sk, w in _models():
        for h in (2.0, 8.0):
            for mnr in (0.2, 0.01):
                for threads in (1, 2):
                    a = osteon.analyze(v, f, sk, w, interval=h, threads=threads,
                                       min_notch_radius=mnr)
                    for field in FIELDS:
                        out[f"{name}|h{h:g}|r{mnr:g}|t{threads}|{field}"] = np.asarray(
                            getattr(a, field))
    bars = {f"bar{rho:g}": stepped_bar(rho) for rho in (1.2, 0.6, 0.12, 0.06, 0.0)}
    bars["cone45"] = stepped_bar(0.0, cone_deg=45.0)
    for name, (v, f) in bars.items():
        for mnr in (0.05, 0.01):
            for threads in (1, 2):
                a = osteon.analyze(v, f, bar_skeleton(), force=1.0, root=0, threads=threads,
                                   min_notch_radius=mnr)
                for field in FIELDS:
                    out[f"{name}|h0|r{mnr:g}|t{threads}|{field}"] = np.asarray(getattr(a, field))
    return out


def _same(x, y) -> bool:
    x, y = np.asarray(x), np.asarray(y)
    return x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes()


def main(argv=None) -> int:
    args = other_build_args(__doc__, argv)
    tests = str(HERE.parent / "tests" / "python")
    dumps = both_dumps(args.other, args.keep, "corners",
                       lambda out: CHILD.format(here=str(HERE), tests=tests, out=out))
    this, other = dumps["this"], dumps["other"]
    bad = 0
    for label, dump in (("this", this), ("other", other)):
        threads = [k for k in dump if "|t1|" in k and not _same(dump[k], dump[k.replace(
            "|t1|", "|t2|")])]
        flagged = sum(int(dump[k].sum()) for k in dump if k.endswith("|t1|notch"))
        print(f"{label}: {flagged} sections with a corner over all runs; "
              f"1 vs 2 threads: {len(threads)} arrays differ")
        bad += len(threads)
    keys = sorted(set(this) | set(other))
    differ = [k for k in keys if k not in this or k not in other or not _same(this[k], other[k])]
    print(f"{len(keys)} arrays; {len(differ)} differ between the builds")
    for run in sorted({k.rsplit("|", 1)[0] for k in differ if k in this and k in other}):
        fields = {f: (this[f"{run}|{f}"], other[f"{run}|{f}"]) for f in FIELDS}
        changed = np.zeros(len(fields["notch"][0]), bool)
        for f in ("notch", "stress_concentration", "notch_radius", "notch_step"):
            changed |= [not _same(x, y) for x, y in zip(*fields[f])]
        for i in np.flatnonzero(changed):
            before, after = ("Kt {:.6g} r {:.6g} D/d {:.6g}".format(
                *(fields[f][side][i] for f in ("stress_concentration", "notch_radius",
                                               "notch_step"))) for side in (1, 0))
            print(f"  {run} s{i}: other {before} -> this {after}")
        if not _same(*fields["stress"]):
            print(f"  {run}: stress differs")
    return 1 if differ or bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
