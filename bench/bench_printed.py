"""Cost of the printed section: analysis time with a print profile vs solid, same model.

    python bench/bench_printed.py [--repeat 7]

The ~100k-face cow x4 (bench/models.py) at h = 2 mm, one thread, process CPU time (steady on a
loaded machine), solid / PrusaSlicer-like FDM (PrintProfile.fdm()) / hollow FDM (0 %) / resin
shell, run interleaved. The target (issue 31): a profile costs at most 15 % over solid.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import osteon
from models import load

PROFILES = {
    "solid": osteon.PrintProfile.solid(),
    "fdm 15 % gyroid": osteon.PrintProfile.fdm(),
    "fdm 0 %": osteon.PrintProfile.fdm(infill=0.0),
    "resin 2 mm": osteon.PrintProfile.resin_hollow(2.0),
}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args(argv)
    v, f, sk, w = load("cow", subdivisions=1)
    times = {name: [] for name in PROFILES}
    for _ in range(args.repeat):
        for name, profile in PROFILES.items():
            t0 = time.process_time()
            a = osteon.analyze(v, f, sk, w, interval=2.0, threads=1, print_profile=profile)
            times[name].append(time.process_time() - t0)
    base = statistics.median(times["solid"])
    print(f"cow x4: {len(f)} faces, {a.num_sections} sections, h = 2 mm, 1 thread, CPU time")
    print("| profile | median (ms) | ratio to solid |")
    print("|---|---|---|")
    for name, t in times.items():
        m = statistics.median(t)
        print(f"| {name} | {1000 * m:.1f} | {m / base:.3f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
