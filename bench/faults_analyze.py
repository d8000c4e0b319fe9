"""Page faults, user and system CPU time per ``osteon.analyze`` of cow x64 (1.5M faces).

    python bench/faults_analyze.py [--h 2] [--repeat 7] [--numpy] [--threads N]

After a warm-up analysis in this process, runs ``--repeat`` analyses and prints the medians of
their wall and process CPU time and of its user and system parts, and the process's minor page
faults per analysis (``getrusage`` around each analysis only, their mean). ``--numpy``: one NumPy
face-area pass (bench_analyze.py's baseline) before each analysis, as bench_analyze.py
interleaves them (its temporaries change which freed memory the analysis gets back).
``OSTEON_OTHER_BUILD=DIR`` imports another build's ``osteon`` package (as compare_builds.py).
The fault count moves with the C library's heap state from one process to the next: compare
builds over several processes, alternating (docs/performance.md, "What big11 changed").
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import sys
import time
from pathlib import Path

if os.environ.get("OSTEON_OTHER_BUILD"):
    # An editable install's import redirect would win over PYTHONPATH: drop it.
    sys.meta_path = [f for f in sys.meta_path if "Redirecting" not in type(f).__name__]
    sys.path.insert(0, os.environ["OSTEON_OTHER_BUILD"])
sys.path.insert(0, str(Path(__file__).resolve().parent))

import osteon
from bench_analyze import numpy_face_area
from models import load


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--h", type=float, default=2.0, help="interval, mm")
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--numpy", action="store_true", help="a NumPy face-area pass before each")
    ap.add_argument("--threads", type=int, default=0)
    args = ap.parse_args(argv)
    v, f, sk, w = load("cow", subdivisions=3)
    kw = {"interval": args.h, "threads": args.threads}
    osteon.analyze(v, f, sk, w, **kw)  # warm up
    wall, cpu, user, system, faults = [], [], [], [], 0
    for _ in range(args.repeat):
        if args.numpy:
            numpy_face_area(v, f)
        r0 = resource.getrusage(resource.RUSAGE_SELF)
        c0, t0 = time.process_time(), time.perf_counter()
        osteon.analyze(v, f, sk, w, **kw)
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
        r1 = resource.getrusage(resource.RUSAGE_SELF)
        faults += r1.ru_minflt - r0.ru_minflt
        user.append(r1.ru_utime - r0.ru_utime)
        system.append(r1.ru_stime - r0.ru_stime)
    med = statistics.median
    print(f"{osteon.__file__}: cow x64 h = {args.h:g} mm, {args.repeat} analyses"
          f"{' after a NumPy pass each' if args.numpy else ''}, load {os.getloadavg()[0]:.1f}: "
          f"wall {med(wall) * 1e3:.1f} ms, CPU {med(cpu) * 1e3:.1f} ms (user "
          f"{med(user) * 1e3:.1f}, system {med(system) * 1e3:.1f}; medians), "
          f"{faults / args.repeat:.0f} page faults per analysis")
    return 0


if __name__ == "__main__":
    sys.exit(main())
