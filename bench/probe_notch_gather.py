"""How many faces the corner search gathers, and how many a flood from the cut would (issue 33).

    python bench/probe_notch_gather.py [--model cow --subdivisions 1] [--interval 2 8]

A measurement for docs/notch.md "Cost" (option (b) of issue 33's cost round: gather the faces
reached through the mesh's connectivity from the thin section's cut instead of every face in
the window). It repeats, in NumPy, `find_steps` and the gathering windows of cpp/src/notch.cpp
from the Analysis's own section arrays (one gathering per thin section and side, the widest
step's window: axial -0.25 ... 1.25 reach from the thin plane, within 2.5 r of the axis; a face
is gathered when a vertex lies inside), then, per gathering, the connected pieces of those faces
(faces joined by a shared vertex): the piece holding the face that crosses the thin plane
nearest the axis ("flood"), and the pieces holding any face crossing the plane within 2 r
("flood, all cut pieces"). Prints one row per gathering and the totals. It counts faces; it does
not search corners (a flood changes which points a sector fits, so it would need its own
comparison). Pure NumPy/SciPy on the Python side: no engine change.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

# cpp/src/notch.cpp / cpp/include/osteon/notch.hpp
STEP_RATIO = 1.1
MIN_SLENDERNESS = 2.0
BODY_SIZED = 0.4
SHAFT_SLENDERNESS = 4.0


def steps_of(a) -> list[dict]:
    """find_steps of cpp/src/notch.cpp on an Analysis: thin section, bone point, r, u, reach."""
    bone = np.asarray(a.section_bone)
    param = np.asarray(a.section_param, float)
    cut = np.asarray(a.section_cut_area, float)
    area = np.asarray(a.section_area, float)
    arm = np.asarray(a.moment_arm, float)
    point = np.asarray(a.section_point, float)
    normal = np.asarray(a.section_normal, float)
    r_model = np.sqrt(cut[cut > 0].max() / np.pi)
    steps = []
    for b in range(int(bone.max()) + 1):
        chain = [i for i in range(len(bone)) if bone[i] == b and cut[i] > 0 and area[i] > 0
                 and np.isfinite(arm[i])]
        chain.sort(key=lambda i: param[i])
        radius = [np.sqrt(cut[i] / np.pi) for i in chain]
        n = len(chain)
        for k in range(n - 1):
            ra, rb = radius[k], radius[k + 1]
            if max(ra, rb) < STEP_RATIO * min(ra, rb):
                continue
            d = 1 if rb > ra else -1
            thin = k if rb > ra else k + 1
            thick = thin + d
            first = thin
            j = thin - d
            while 0 <= j < n:
                if radius[j] >= radius[thin] or \
                        abs(param[chain[j]] - param[chain[first]]) > 0.6 * radius[first]:
                    break
                thin = j
                j -= d
            i = chain[thin]
            r_thin = np.sqrt(area[i] / np.pi)
            if arm[i] < MIN_SLENDERNESS * r_thin:
                continue
            if r_thin >= BODY_SIZED * r_model and arm[i] < SHAFT_SLENDERNESS * r_thin:
                continue
            u = normal[i].copy()
            towards = point[chain[thick]] - point[i]
            if towards @ u < 0:
                u = -u
            steps.append({"section": i, "point": point[i], "r": r_thin, "u": u,
                          "reach": max(float(towards @ u), 0.0)})
    return steps


def gatherings(steps: list[dict]) -> list[dict]:
    """One per thin section and side, over its widest step's window (measure_corners)."""
    out = {}
    for st in steps:
        key = (st["section"], tuple(st["u"]))
        if key in out:
            out[key]["reach"] = max(out[key]["reach"], st["reach"])
        else:
            out[key] = dict(st)
    return list(out.values())


def probe(v: np.ndarray, f: np.ndarray, g: dict) -> tuple[int, int, int]:
    """(faces gathered, faces of the flood from the nearest cut face, of all cut pieces)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    d = v - g["point"]
    ax = d @ g["u"]
    t = np.linalg.norm(d - np.outer(ax, g["u"]), axis=1)
    r, reach = g["r"], g["reach"]
    inside = (ax >= -0.25 * reach) & (ax <= 1.25 * reach) & (t <= 2.5 * r)
    kf = f[inside[f].any(1)]
    nk = len(kf)
    rows = np.repeat(np.arange(nk), 3)
    graph = coo_matrix((np.ones(3 * nk), (rows, nk + kf.ravel())), shape=(nk + len(v),) * 2)
    _, label = connected_components(graph, directed=False)
    fa = ax[kf]
    cuts = np.nonzero((fa.min(1) < 0) & (fa.max(1) > 0) & (t[kf].max(1) <= 2.0 * r))[0]
    if len(cuts) == 0:
        return nk, 0, 0
    nearest = cuts[np.argmin(t[kf][cuts].mean(1))]
    flood = int((label[:nk] == label[nearest]).sum())
    flood_all = int(np.isin(label[:nk], np.unique(label[cuts])).sum())
    return nk, flood, flood_all


def main(argv=None) -> int:
    import osteon
    from models import load

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default="cow")
    ap.add_argument("--subdivisions", type=int, default=1)
    ap.add_argument("--interval", type=float, nargs="+", default=[2.0, 8.0])
    args = ap.parse_args(argv)
    v, f, sk, w = load(args.model, subdivisions=args.subdivisions)
    v, f = np.asarray(v, float), np.asarray(f, np.int64)
    print(f"{args.model} x{4 ** args.subdivisions}: {len(f)} faces")
    print("| h (mm) | section | r (mm) | reach (mm) | gathered | flood | flood, all cut pieces |")
    print("|---|---|---|---|---|---|---|")
    for h in args.interval:
        a = osteon.analyze(v, f, sk, w, interval=h, threads=1)
        total = np.zeros(3, int)
        gs = gatherings(steps_of(a))
        for g in gs:
            row = probe(v, f, g)
            total += row
            print(f"| {h:g} | {g['section']} | {g['r']:.2f} | {g['reach']:.2f} | {row[0]} | "
                  f"{row[1]} | {row[2]} |")
        print(f"| {h:g} | all {len(gs)} | | | {total[0]} | {total[1]} "
              f"({total[1] / total[0] - 1:+.1%}) | {total[2]} ({total[2] / total[0] - 1:+.1%}) |",
              flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
