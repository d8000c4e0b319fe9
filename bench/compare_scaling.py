"""Both-axes (the paper's) vs thin-direction correction on the closed real models.

    python bench/compare_scaling.py [--load 2.0]

Each model is scaled to a 120 mm print under 20 N with the allowable stress set to its peak
stress / ``--load``, so that it must be thickened. For each scaling mode prints: converged,
rounds, volume added (%), largest and mean vertex displacement (mm), and how much the parts
that moved changed their width across the bone (the largest section extent, mean over moved
sections) against their thickness: thin-direction scaling is meant to keep widths (shapes) and
add less material. Also the median correction time.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import osteon
from models import load

MODELS = ["arm", "elephant", "cheburashka", "cow", "rignet2982", "rignet11814"]


def width_change(before: osteon.Analysis, after: osteon.Analysis) -> float:
    """Mean relative change (%) of sqrt(area * aspect) (a section's width) over the sections
    whose area changed by more than 0.1 %."""
    a0, a1 = before.section_area, after.section_area
    ok = np.isfinite(before.section_aspect) & np.isfinite(after.section_aspect) & (a0 > 0)
    changed = ok & (np.abs(a1 - a0) > 1e-3 * a0)
    if not changed.any():
        return 0.0
    w0 = np.sqrt(a0[changed] * before.section_aspect[changed])
    w1 = np.sqrt(a1[changed] * after.section_aspect[changed])
    return float(100 * np.mean(w1 / w0 - 1))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--load", type=float, default=2.0, help="peak stress / allowable stress")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    print("| model | scaling | converged | rounds | volume added (%) | max displacement (mm) | "
          "mean displacement (mm) | width change (%) | time (ms) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name in MODELS:
        v, f, sk, w = load(name)
        allowable = osteon.analyze(v, f, sk, w, force=20.0).max_stress / args.load
        for scaling in ("uniform", "thin"):
            kw = {"force": 20.0, "allowable_stress": allowable, "scaling": scaling}
            fix = osteon.correct(v, f, sk, w, **kw)
            times = []
            for _ in range(args.repeat):
                t0 = time.perf_counter()
                osteon.correct(v, f, sk, w, **kw)
                times.append(time.perf_counter() - t0)
            moved = np.linalg.norm(fix.vertices - v, axis=1)
            mean_moved = float(moved[moved > 0].mean()) if (moved > 0).any() else 0.0
            print(f"| {name} | {scaling} | {fix.converged} | {len(fix.rounds)} | "
                  f"{fix.volume_change_percent:.2f} | {fix.max_displacement:.2f} | "
                  f"{mean_moved:.3f} | {width_change(fix.before, fix.after):.1f} | "
                  f"{statistics.median(times) * 1e3:.1f} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
