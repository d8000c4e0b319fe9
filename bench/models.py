"""Benchmark models: the real rigged models of tests/data (tests/python/rigged_models.py: loaded
by name, scaled to a 120 mm print, subdivided for the ~100k and 1M+ face sizes) and the
benchmarks' common options."""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "python"))
from rigged_models import DATA, load, subdivide

__all__ = ["CASES", "DATA", "load", "median_time", "model_cases", "subdivide"]


def median_time(fn, repeat: int) -> float:
    """Median wall time in seconds of ``repeat`` calls of ``fn()``."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


#: the speed table's models: (name, Loop subdivisions); the last is the 1M+ face cow
CASES = [("rignet2982", 0), ("arm", 0), ("cow", 1), ("cow", 3)]


def model_cases(description: str, argv=None, cpu_option: bool = False):
    """The model benchmarks' common options (--repeat, --quick, with ``cpu_option`` --cpu) ->
    (args, [(name, subdivisions)])."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--repeat", type=int, default=9)
    ap.add_argument("--quick", action="store_true", help="skip the 1M+ face model")
    if cpu_option:
        ap.add_argument("--cpu", action="store_true",
                        help="one thread, process CPU time (steadier on a loaded machine)")
    args = ap.parse_args(argv)
    return args, CASES[:3] if args.quick else list(CASES)
