"""Every rigged model of tests/data at the PrusaSlicer-like default print vs solid (issue 31).

    python bench/printed_models.py

Each model scaled to 120 mm, PLA-like allowable 60 MPa (the engine's default), 20 N, h = 2 mm,
built along +Z: the largest stress and the weak bones with the section solid and as printed
with ``PrintProfile.fdm()`` (2 x 0.45 mm perimeters, 0.2 mm layers, 4 top/bottom layers, 15 %
gyroid, solid under 70 mm²). Prints a markdown table.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import osteon
from osteon.io import load_model

DATA = Path(__file__).resolve().parents[1] / "tests" / "data"
HIS = DATA / "Hyperspectral-Inverse-Skinning"
MODELS = [
    ("cow", HIS / "cow_clean.obj", HIS / "cow.tgf", HIS / "cow.DMAT"),
    ("wolf", HIS / "wolf_clean.obj", HIS / "wolf.tgf", HIS / "wolf.DMAT"),
    ("cheburashka", HIS / "cheburashka.obj", HIS / "cheburashka.tgf", HIS / "cheburashka.DMAT"),
    ("cylinder", HIS / "cylinder.obj", HIS / "cylinder.tgf", HIS / "cylinder.DMAT"),
    ("arm", DATA / "libigl-tutorial-data/arm.obj", None, None),
    ("elephant", DATA / "libigl-tutorial-data/elephant.obj", None, None),
    ("Fox", DATA / "glTF-Sample-Models/Fox.glb", None, None),
] + [(f"RigNet {p.stem.split('_')[0]}", p, None, None)
     for p in sorted((DATA / "RigNet").glob("*_ori.obj"))]


def weak_names(a) -> list[str]:
    return [row["bone"] for row in a.weak_bones()]


def main() -> int:
    print("| model | faces | max stress solid (MPa) | printed (MPa) | ratio | weak bones solid "
          "| weak bones printed (new) |")
    print("|---|---|---|---|---|---|---|")
    for name, mesh, skel, weights in MODELS:
        try:
            m = load_model(mesh, skeleton=skel, weights=weights)
        except (ValueError, OSError) as err:
            print(f"| {name} | - | not loaded: {err} | | | | |")
            continue
        v, f = np.asarray(m.vertices), np.asarray(m.faces, dtype=np.int32)
        sk = m.skeleton if isinstance(m.skeleton, osteon.Skeleton) else osteon.Skeleton(
            m.heads, m.tails, m.parents, m.bone_names)
        solid = osteon.analyze(v, f, sk, m.weights)
        printed = osteon.analyze(v, f, sk, m.weights, print_profile=osteon.PrintProfile.fdm())
        ws, wp = weak_names(solid), weak_names(printed)
        new = [b for b in wp if b not in ws]
        print(f"| {name} | {len(f)} | {solid.max_stress:.1f} | {printed.max_stress:.1f} | "
              f"{printed.max_stress / solid.max_stress:.2f} | {len(ws)} | {len(wp)}"
              f"{' (' + ', '.join(new[:6]) + (' ...' if len(new) > 6 else '') + ')' if new else ''} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
