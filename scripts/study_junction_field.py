"""Study (issue 16, docs/validation.md "Limb roots: the FEM field on the plane"): how is the
load really carried across a junction plane, and does the limb's own flare, continued to the
plane, predict it?

For each junction section of the validation table it runs the FEM cross-check (crop mode,
elements r/3 near the plane, F = 20 N) with ``keep_field=True`` and reads the worst-direction
σ_nn over the plane as a function of the distance from the core's centroid, in core radii
r = √(core area / π):

* where the peak lies, and how far out the plane carries load (the last ring of width r/4
  whose peak is above 5 % of the plane's peak);
* the radius of the round section that beam theory would need to give the FEM peak,
  R = (4 F d / (π σ_FEM))^(1/3) (d: osteon's moment arm);
* the limb's own radius continued to the plane: the whole cuts of the three sections on the
  limb side (the side whose neighbours are plain, not junction, sections), r(h), r(2h), r(3h),
  extrapolated quadratically, 3 r(h) - 3 r(2h) + r(3h); and the stress osteon would give with
  that radius (σ_core (r / r_flare)³: an equivalent-radius estimate, not the engine's W).

Not part of the tests and not used by osteon. Needs gmsh and ccx, ``pip install shapely`` and
the shared models (``--data DIR``: the folder of ``SOURCES.md``); ~1-5 min a section.
Run: ``python scripts/study_junction_field.py [--data DIR] [--rig DIR]``
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from study_limb_root_spread import CASES, around_origin, plane_frame, region

FORCE_N = 20.0


def flare_radius(a, s):
    """The limb's whole-cut radius continued to section s (mm), from the 3 plain sections on the
    side that has them; None when neither side has 3."""
    family = set(np.flatnonzero(a.section_bone == a.section_bone[s]).tolist())
    for side in (1, -1):
        near = [s + side * i for i in (1, 2, 3)]
        if all(j in family and not a.junction[j] for j in near):
            r1, r2, r3 = np.sqrt(a.section_cut_area[near] / np.pi)
            return 3 * r1 - 3 * r2 + r3
    return None


def field_profile(points, sigma, centre, r_core):
    """(peak MPa, peak distance / r, engaged distance / r) of the plane's worst-direction σ."""
    dist = np.linalg.norm(points - centre, axis=1) / r_core
    peak = float(sigma.max())
    rings = np.floor(dist / 0.25).astype(int)
    engaged = max((k + 1) * 0.25 for k in np.unique(rings) if sigma[rings == k].max() > 0.05 * peak)
    return peak, float(dist[np.argmax(sigma)]), engaged


def main(data, rig=None):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "python"))
    import osteon
    from osteon import fem
    from osteon.cli import common
    from osteon.cli.parser import build_parser

    data = Path(data)
    if not (data / "SOURCES.md").is_file():
        raise SystemExit(f"study_junction_field: the shared models are not at {data} "
                         "(give their folder with --data DIR)")
    cases = {k: ([str(data / x) if x.endswith((".obj", ".tgf", ".txt")) else x for x in argv],
                 sections) for k, (argv, sections) in CASES.items()}
    if rig is not None:
        cases["junction rig (real stubs)"] = (
            [f"{rig}/junction_rig.obj", "--skeleton", f"{rig}/junction_rig.tgf",
             "--height-mm", "90"], {4: None, 6: None})
    print("| model | section | osteon (core) MPa | FEM peak MPa | peak at (r) | load carried "
          "to (r) | beam radius for the FEM peak (r) | limb flare at the plane (r) | σ on the "
          "flare MPa (vs FEM) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, (argv, sections) in cases.items():
        args = build_parser().parse_args(["validate", *argv])
        settings, model = common.settings_from_args(args), common.load_model_of(args)
        positional, keyword = common.engine_args(settings, model)
        a = osteon.analyze(*positional, **keyword, keep_outlines=True)
        picked = fem.pick_sections(a, model.heads, model.tails, n=50, tiers=((0.0, 2.0),),
                                   junctions=True)
        for s in sections:
            sec = [p for p in picked if p["index"] == s]
            if not sec:
                print(f"| {name} | {s} | not picked by `validate --junctions` |")
                continue
            rep = fem.cross_check(model.vertices, model.faces, sec, force=FORCE_N, threads=1,
                                  keep_field=True)
            if not rep.sections:
                print(f"| {name} | {s} | FEM failed: {rep.failed} |")
                continue
            x = rep.sections[0]
            origin, (u, v) = a.section_point[s], plane_frame(a.section_normal[s])
            core = around_origin(region(a.section_loops[s], origin, u, v))
            r_core = np.sqrt(core.area / np.pi)
            centre = origin + core.centroid.x * u + core.centroid.y * v
            sigma = np.linalg.norm(x.extra["field_mpa_per_n"], axis=0) * FORCE_N
            peak, at, engaged = field_profile(x.extra["field_points_mm"], sigma, centre, r_core)
            beam_r = (4 * FORCE_N * x.moment_arm_mm / (np.pi * peak)) ** (1 / 3) / r_core
            flare = flare_radius(a, s)
            if flare is None:
                cells = "no plain limb side | —"
            else:
                on_flare = a.stress[s] * (r_core / max(flare, r_core)) ** 3
                cells = (f"{flare / r_core:.2f} | {on_flare:.2f} "
                         f"({100 * (on_flare / peak - 1):+.0f} %)")
            print(f"| {name} | {s} | {a.stress[s]:.2f} | {peak:.2f} | {at:.2f} | {engaged:.2f} | "
                  f"{beam_r:.2f} | {cells} |", flush=True)


if __name__ == "__main__":
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", required=True,
                        help="the shared models' folder (the one holding SOURCES.md)")
    parser.add_argument("--rig", help="folder of make_junction_rig.py's output")
    ns = parser.parse_args()
    main(ns.data, ns.rig)
