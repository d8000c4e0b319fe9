"""Study (issue 16, docs/validation.md "Limb roots: a spread model, studied"): would a load that
spreads at a fixed angle through the material next to a junction bring osteon's junction
sections within 20 % of FEM?

For each junction section of the validation table it rebuilds osteon's core from the bone's own
sections at every interval h between the section and its neighbour planes (±δ), letting the
region a load path can reach grow by ``K · h`` per slice *inside the material of that slice*
(``K = 1``: 45°; ``K = 0``: no spread, which reproduces osteon's core), and prints the stress
the spread core would give next to the FEM peak on the same plane (the FEM numbers are the
``osteon validate --fem --junctions`` readings of docs/validation.md).

Not part of the tests and not used by osteon. Needs ``pip install shapely`` and the shared
models (``--data DIR``: the folder of ``SOURCES.md``, e.g. ``../shared/data``); the junction rig's real stubs are
added with ``--rig DIR`` (the output of ``python scripts/make_junction_rig.py DIR``). Run:
``python scripts/study_limb_root_spread.py [--data DIR] [--rig DIR] [K ...]``
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

# model arguments (as for `osteon validate`), junction sections, FEM peak on the plane (MPa)
CASES = {
    "elephant (limb root)": (["libigl-tutorial-data/elephant.obj"], {10: 0.78}),
    "cheburashka (forearm fused to the torso)": (
        ["Hyperspectral-Inverse-Skinning/cheburashka.obj"], {20: 4.85}),
    "cow_clean (leg roots)": (
        ["Hyperspectral-Inverse-Skinning/cow_clean.obj",
         "--skeleton", "Hyperspectral-Inverse-Skinning/cow.tgf"], {78: 9.19, 49: 9.56, 153: 41.6}),
    "dog 2982 (shoulder, a neck 2 mm away)": (
        ["RigNet/2982_ori.obj", "--skeleton", "RigNet/2982_ori_rig.txt"], {28: 61.8}),
}


def plane_frame(normal):
    """(u, v) of osteon's section plane (PlaneFrame::make): the world axis least aligned with
    the normal, made orthogonal."""
    n = normal / np.linalg.norm(normal)
    a = np.abs(n)
    helper = np.eye(3)[0 if a[0] <= a[1] and a[0] <= a[2] else (1 if a[1] <= a[2] else 2)]
    u = helper - helper.dot(n) * n
    u /= np.linalg.norm(u)
    return u, np.cross(n, u)


def region(loops, origin, u, v):
    """A shapely polygon of a section's loops (outer first), in (u, v) mm around origin."""
    from shapely.geometry import Polygon

    rings = [np.c_[(p - origin) @ u, (p - origin) @ v] for p in loops]
    return Polygon(rings[0], rings[1:]).buffer(0)


def around_origin(geometry):
    """The part of a (multi)polygon holding the bone point (0, 0), else the largest part."""
    from shapely.geometry import Point

    parts = list(getattr(geometry, "geoms", [geometry]))
    for p in parts:
        if p.buffer(1e-9).contains(Point(0.0, 0.0)):
            return p
    return max(parts, key=lambda p: p.area)


def area_and_modulus(poly):
    """(A mm², W mm³) with osteon's W: 1 / max over vertices |J⁻¹ (p - c)| (section.cpp)."""
    rings = [np.asarray(poly.exterior.coords)] + [np.asarray(r.coords) for r in poly.interiors]
    a = sx = sy = ixx = iyy = ixy = 0.0
    for k, r in enumerate(rings):
        x, y, x1, y1 = r[:-1, 0], r[:-1, 1], r[1:, 0], r[1:, 1]
        c = x * y1 - x1 * y
        sign = 1.0 if (c.sum() > 0) == (k == 0) else -1.0
        a += sign * c.sum() / 2
        sx += sign * ((x + x1) * c).sum() / 6
        sy += sign * ((y + y1) * c).sum() / 6
        ixx += sign * ((x * x + x * x1 + x1 * x1) * c).sum() / 12
        iyy += sign * ((y * y + y * y1 + y1 * y1) * c).sum() / 12
        ixy += sign * ((x * y1 + 2 * x * y + 2 * x1 * y1 + x1 * y) * c).sum() / 24
    cx, cy = sx / a, sy / a
    j = np.array([[ixx - a * cx * cx, ixy - a * cx * cy], [ixy - a * cx * cy, iyy - a * cy * cy]])
    pts = np.vstack(rings) - [cx, cy]
    return a, 1.0 / np.sqrt((np.linalg.solve(j, pts.T) ** 2).sum(0).max())


def spread_core(a, s, k):
    """The section's material a load path reaches from both neighbour planes, growing by k·h
    per slice inside each slice's material (a side past the bone's end: not restricted)."""
    bone = a.section_bone[s]
    family = set(np.flatnonzero(a.section_bone == bone).tolist())
    origin, (u, v) = a.section_point[s], plane_frame(a.section_normal[s])
    cut = a.section_cut_loops
    whole = region(cut[s], origin, u, v)
    radius = np.sqrt(np.median(a.section_cut_area[sorted(family)]) / np.pi)
    h, m = a.interval, max(1, round(1.25 * radius / a.interval))
    margin = 0.05 * radius
    core = whole
    for side in (-1, 1):
        slices = [s + side * i for i in range(1, m + 1)]
        if any(j not in family for j in slices):
            continue
        regions = [region(cut[j] or a.section_loops[j], origin, u, v) for j in slices]
        reach = regions[-1].buffer(margin)
        for r in reversed(regions[:-1]):
            reach = around_origin(reach.buffer(k * h).intersection(r.buffer(margin)))
        core = core.intersection(reach.buffer(k * h))
    return around_origin(core)


def main(spreads, rig, data):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "python"))
    import osteon
    from osteon.cli import common
    from osteon.cli.parser import build_parser

    data = Path(data)
    if not (data / "SOURCES.md").is_file():
        raise SystemExit(f"study_limb_root_spread: the shared models are not at {data} "
                         "(give their folder with --data DIR)")
    try:
        import shapely  # noqa: F401
    except ImportError:
        raise SystemExit("study_limb_root_spread: needs shapely (pip install shapely)") from None
    print("| model | section | FEM (MPa) | " + " | ".join(f"K = {k:g}" for k in spreads) + " |")
    print("|---|---|---|" + "---|" * len(spreads))
    cases = {k: ([str(data / x) if x.endswith((".obj", ".tgf", ".txt")) else x for x in argv],
                 sections) for k, (argv, sections) in CASES.items()}
    if rig is not None:
        cases["junction rig (real stubs: the spine through the hip bar)"] = (
            [f"{rig}/junction_rig.obj", "--skeleton", f"{rig}/junction_rig.tgf",
             "--height-mm", "90"], {4: 35.9, 6: 31.3})
    for name, (argv, sections) in cases.items():
        args = build_parser().parse_args(["validate", *argv])
        settings, model = common.settings_from_args(args), common.load_model_of(args)
        positional, keyword = common.engine_args(settings, model)
        a = osteon.analyze(*positional, **keyword, keep_outlines=True)
        for s, fem in sections.items():
            _, w_core = area_and_modulus(around_origin(region(a.section_loops[s],
                                                              a.section_point[s],
                                                              *plane_frame(a.section_normal[s]))))
            cells = []
            for k in spreads:
                area, w = area_and_modulus(spread_core(a, s, k))
                sigma = a.stress[s] * w_core / w
                cells.append(f"{sigma:.2f} ({100 * (sigma / fem - 1):+.0f} %, A {area:.0f})")
            print(f"| {name} | {s} | {fem} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("spreads", nargs="*", type=float, metavar="K",
                        help="spread per slice, x h (default: 0 0.5 1)")
    parser.add_argument("--data", required=True,
                        help="the shared models' folder (the one holding SOURCES.md)")
    parser.add_argument("--rig", help="folder of make_junction_rig.py's output")
    ns = parser.parse_args()
    main(ns.spreads or [0.0, 0.5, 1.0], ns.rig, ns.data)
