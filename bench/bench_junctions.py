"""Cost of the junction cores (docs/junctions.md): ``osteon.analyze`` with ``junctions=True``
(the default) vs ``junctions=False`` (whole cuts, the analysis before issue 16), run
interleaved in the same process.

    python bench/bench_junctions.py [--repeat 9] [--quick] [--cpu]

Prints per model and interval h the median times, their ratio (target <= 1.10) and the number
of junction sections found; then the same for a live update (an ``osteon.Analyzer`` re-run after
the vertices of the bone with the fewest vertices moved by 0.5 mm: a posed limb, the partial run
of live mode, docs/method.md, Targets), with the junction checks that update re-made.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import numpy as np
import osteon
from models import load, model_cases


def live_update(v, f, sk, w, h, junctions, repeat, clock, threads):
    """Median time (s) of an Analyzer re-run after one limb's vertices move by 0.5 mm (the
    bone with the fewest dominant vertices), alternating with the rest pose."""
    an = osteon.Analyzer(f, len(v), sk, w, interval=h, junctions=junctions, threads=threads)
    dominant = np.asarray(w.argmax(axis=1)).ravel()
    counts = np.bincount(dominant, minlength=sk.num_bones)
    limb = int(np.argmin(np.where(counts > 0, counts, np.iinfo(np.int64).max)))
    moved = v.copy()
    moved[dominant == limb] += 0.5
    an.run(v)
    times = []
    for k in range(repeat):
        t0 = clock()
        an.run(moved if k % 2 == 0 else v)
        times.append(clock() - t0)
    return statistics.median(times)


def main(argv=None) -> int:
    args, cases = model_cases(__doc__.splitlines()[0], argv, cpu_option=True)
    clock = time.process_time if args.cpu else time.perf_counter
    threads = 1 if args.cpu else 0
    print("| model | faces | h (mm) | sections | junction sections | whole cuts median (ms) "
          "| junction cores median (ms) | ratio |")
    print("|---|---|---|---|---|---|---|---|")
    for name, subdivisions in cases:
        v, f, sk, w = load(name, subdivisions=subdivisions)
        for h in (2.0, 8.0):
            def run(junctions, v=v, f=f, sk=sk, w=w, h=h):
                return osteon.analyze(v, f, sk, w, interval=h, junctions=junctions,
                                      threads=threads)

            a = run(True)
            times = {False: [], True: []}
            for _ in range(args.repeat):
                for j in (False, True):
                    t0 = clock()
                    run(j)
                    times[j].append(clock() - t0)
            off, on = (1000 * statistics.median(times[k]) for k in (False, True))
            print(f"| {name} | {len(f)} | {h:g} | {a.num_sections} | {int(a.junction.sum())} "
                  f"| {off:.1f} | {on:.1f} | {on / off:.3f} |")
    print()
    print("Live update (Analyzer re-run, one limb moved 0.5 mm):")
    print()
    print("| model | faces | h (mm) | whole cuts median (ms) | junction cores median (ms) | ratio |")
    print("|---|---|---|---|---|---|")
    for name, subdivisions in cases:
        v, f, sk, w = load(name, subdivisions=subdivisions)
        for h in (2.0, 8.0):
            off, on = (1000 * live_update(v, f, sk, w, h, j, args.repeat, clock, threads)
                       for j in (False, True))
            print(f"| {name} | {len(f)} | {h:g} | {off:.1f} | {on:.1f} | {on / off:.3f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
