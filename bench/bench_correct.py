"""Correction speed: ``osteon.correct`` on a ~17k-face and a ~100k-face model (120 mm print,
20 N, allowable stress set to half the model's peak so that it has to be thickened).

    python bench/bench_correct.py [--repeat 5]

Prints the median time, rounds taken and, as a same-process baseline, the median of one
``osteon.analyze`` of the same mesh (a correction costs a few analyses).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import osteon
from models import load, median_time


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args(argv)
    print("| model | faces | rounds | converged | correct median (ms) | analyze median (ms) | ratio |")
    print("|---|---|---|---|---|---|---|")
    for name, subdiv in [("arm", 0), ("elephant", 0), ("cow", 1)]:
        v, f, sk, w = load(name, subdivisions=subdiv)
        allowable = osteon.analyze(v, f, sk, w, force=20.0).max_stress / 2
        fix = osteon.correct(v, f, sk, w, force=20.0, allowable_stress=allowable)
        kw = {"force": 20.0, "allowable_stress": allowable}
        t_fix = median_time(lambda v=v, f=f, sk=sk, w=w, kw=kw: osteon.correct(v, f, sk, w, **kw),
                            args.repeat)
        t_an = median_time(lambda v=v, f=f, sk=sk, w=w, kw=kw: osteon.analyze(v, f, sk, w, **kw),
                           args.repeat)
        label = name if subdiv == 0 else f"{name} x{4 ** subdiv}"
        print(f"| {label} | {len(f)} | {len(fix.rounds)} | {fix.converged} | {t_fix * 1e3:.1f} | "
              f"{t_an * 1e3:.1f} | {t_fix / t_an:.1f} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
