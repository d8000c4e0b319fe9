"""Analysis speed vs one NumPy face-area pass over the same mesh, in the same process.

    python bench/bench_analyze.py [--repeat 9] [--quick]

For each model and interval h (2 mm, 8 mm) prints the median time of ``osteon.analyze`` and of
the NumPy baseline (gather the triangles, cross product, norm, sum), run interleaved, and their
ratio (analysis / NumPy; the targets, issue 34: <= 0.5 for the ~100k-face model at h = 2 mm,
<= 0.35 for the 1.5M-face one).

Wall times move with the machine's load (printed first, with the cores): the last two columns
are the process CPU time of each (all threads; medians of the same runs), which other processes
slow less (osteon's CPU time / its wall time tells how many cores it kept busy).

The NumPy pass allocates ~10 large temporaries; whether they come back as fresh pages (page
faults) or recycled heap memory depends on the allocator's state, so its time is bimodal
(e.g. 10 or 17 ms at 93k faces, in different processes). The last column is therefore the
ratio to NumPy's *fastest* run in the same process, the strict reading of the target.
"""

from __future__ import annotations

import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import osteon
from models import load, model_cases


def numpy_face_area(vertices: np.ndarray, faces: np.ndarray) -> float:
    """The baseline: total surface area, mm^2, the way a NumPy user writes it."""
    tri = vertices[faces]
    return 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum()


def interleaved(fns, repeat: int, cpu: list[list[float]] | None = None) -> list[list[float]]:
    """Wall times of each function, run interleaved `repeat` times, seconds (and, into `cpu`
    when given, the process CPU time of each run)."""
    times = [[] for _ in fns]
    for _ in range(repeat):
        for i, fn in enumerate(fns):
            c0, t0 = time.process_time(), time.perf_counter()
            fn()
            times[i].append(time.perf_counter() - t0)
            if cpu is not None:
                cpu[i].append(time.process_time() - c0)
    return times


def median_interleaved(fns, repeat: int) -> list[float]:
    return [statistics.median(t) for t in interleaved(fns, repeat)]


def main(argv=None) -> int:
    args, cases = model_cases(__doc__.splitlines()[0], argv)
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    print("| model | faces | bones | h (mm) | sections | osteon median (ms) | NumPy face-area median "
          "(ms) | ratio | NumPy fastest (ms) | ratio to fastest | osteon CPU (ms) | NumPy CPU "
          "(ms) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name, subdiv in cases:
        v, f, sk, w = load(name, subdivisions=subdiv)
        label = name if subdiv == 0 else f"{name} x{4 ** subdiv}"
        for h in (2.0, 8.0):
            res = osteon.analyze(v, f, sk, w, interval=h)  # warm up
            cpu = [[], []]
            times = interleaved(
                [lambda v=v, f=f, sk=sk, w=w, h=h: osteon.analyze(v, f, sk, w, interval=h),
                 lambda v=v, f=f: numpy_face_area(v, f)], args.repeat, cpu)
            t_osteon, t_numpy = (statistics.median(t) for t in times)
            c_osteon, c_numpy = (statistics.median(c) for c in cpu)
            fastest = min(times[1])
            print(f"| {label} | {len(f)} | {sk.num_bones} | {h:g} | {res.num_sections} | "
                  f"{t_osteon * 1e3:.2f} | {t_numpy * 1e3:.2f} | {t_osteon / t_numpy:.2f} | "
                  f"{fastest * 1e3:.2f} | {t_osteon / fastest:.2f} | {c_osteon * 1e3:.2f} | "
                  f"{c_numpy * 1e3:.2f} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
