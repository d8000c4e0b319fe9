"""Best build direction speed: ``osteon.best_orientation`` on real models at 120 mm (the cow ×4
is the ~100k-face one) for thousands of candidate directions, against one ``osteon.analyze`` of
the same mesh in the same process (the sections are cut once; orienting only re-weighs them).

    python bench/bench_orientation.py [--repeat 5] [--samples 4000] [--ratio 0.55]

Prints, per model, the median times, their ratio, and the worst stress ratio printed along the
model's +Z vs along the best direction found (and with 4x the samples, as a convergence check).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import osteon
from models import load, median_time
from osteon.orientation import best_orientation


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--samples", type=int, default=4000)
    ap.add_argument("--ratio", type=float, default=0.55, help="layer strength ratio Z/X (PLA)")
    ap.add_argument("--models", default="rignet2982,arm,elephant,cheburashka,cow,cow:1")
    args = ap.parse_args(argv)
    print(f"samples {args.samples}, layer ratio {args.ratio}, medians of {args.repeat}")
    print("| model | faces | sections | best_orientation (ms) | analyze (ms) | ratio | "
          "worst ratio +Z | best | best (4x samples) | direction |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    kw = {"force": 20.0, "allowable_stress": 60.0}
    for spec in args.models.split(","):
        name, _, sub = spec.partition(":")
        subdiv = int(sub or 0)
        v, f, sk, w = load(name, subdivisions=subdiv)
        a = osteon.analyze(v, f, sk, w, **kw)
        t_an = median_time(lambda v=v, f=f, sk=sk, w=w: osteon.analyze(v, f, sk, w, **kw),
                           args.repeat)
        run = lambda a=a: best_orientation(a, samples=args.samples,
                                           layer_strength_ratio=args.ratio)
        t_or = median_time(run, args.repeat)
        o = run()
        fine = best_orientation(a, samples=4 * args.samples, layer_strength_ratio=args.ratio)
        label = name if subdiv == 0 else f"{name} x{4 ** subdiv}"
        d = ", ".join(f"{x:+.2f}" for x in o.direction)
        print(f"| {label} | {len(f)} | {a.num_sections} | {t_or * 1e3:.1f} | {t_an * 1e3:.1f} | "
              f"{t_or / t_an:.2f} | {o.reference_ratio:.3f} | {o.worst_ratio:.3f} | "
              f"{fine.worst_ratio:.3f} | ({d}) |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
