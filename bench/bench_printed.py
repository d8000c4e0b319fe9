"""Cost of the printed section: analysis time with a print profile vs solid, same model.

    python bench/bench_printed.py [--repeat 7]
    python bench/bench_printed.py --wall [--threads 2] [--repeat 15]
    python bench/bench_printed.py --instructions [OTHER_PYTHONPATH]

The ~100k-face cow x4 (bench/models.py) at h = 2 mm, one thread, process CPU time (steady on a
loaded machine), solid / PrusaSlicer-like FDM (PrintProfile.fdm()) / hollow FDM (0 %) / resin
shell, run interleaved. The target (issue 31): a profile costs at most 15 % over solid.

``--wall``: wall time (what a user waits for) instead of CPU time, with ``--threads`` workers
(default 2, both cores), the machine's load average printed before and after.

``--instructions``: instead of times, the engine's instructions for one analysis per profile
(callgrind, as bench/compare_builds.py --instructions counts them; needs valgrind), their ratio
to solid, and from the same run the inclusive counts of the printed section
(``osteon::printed_section``), of its own polygon passes (``winding_region``), of Clipper2's
boolean passes (its offsets' union included) and of the skin widening. Exact whatever
the machine's load. OTHER_PYTHONPATH: another build's ``osteon`` package instead.
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

# Inclusive counts read from callgrind_annotate, by the start of the function's name.
PARTS = {
    "printed section": "osteon::printed_section(",
    "winding_region": "osteon::detail::winding_region(",
    "Clipper2 passes": "Clipper2Lib::ClipperBase::ExecuteInternal(",
    "skin widening": "osteon::detail::widened_skin_strips(",
}


def instructions(other: str | None) -> int:
    """One analysis per profile under callgrind: a markdown table of instruction counts."""
    import os
    import subprocess
    import tempfile

    from compare_builds import HERE, PREAMBLE, callgrind

    env = dict(os.environ)
    if other:
        env["OSTEON_OTHER_BUILD"] = other
    rows, base = [], None
    for name in PROFILES:
        code = PREAMBLE.format(here=str(HERE), model="cow", sub=1, no_junctions=False) + (
            "from bench_printed import PROFILES\n"
            f"osteon.analyze(v, f, sk, w, interval=2.0, threads=1, print_profile=PROFILES[{name!r}])\n"
            "print(osteon.__file__)\n")
        env["PYTHONPATH"] = str(Path(__file__).resolve().parent)
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "callgrind.out")
            total, stdout = callgrind(code, env, out)
            listing = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100",
                                      out], capture_output=True, text=True, check=True).stdout
        file = stdout.strip().splitlines()[-1]
        if other and not file.startswith(other):
            raise SystemExit(f"the other build was not imported: {file}")
        parts = {}
        for part, symbol in PARTS.items():
            parts[part] = sum(int(line.split()[0].replace(",", "")) for line in listing.splitlines()
                              if len(line.split()) > 1 and symbol in line.split(None, 1)[1]
                              and line.split(None, 1)[1].split(":", 1)[-1].lstrip().startswith(symbol))
        base = base or total
        rows.append((name, total, parts))
    print("cow x4, h = 2 mm, 1 thread, engine instructions (M); parts inclusive")
    print("| profile | analysis | ratio to solid | " + " | ".join(PARTS) + " |")
    print("|---|---|---|" + "---|" * len(PARTS))
    for name, total, parts in rows:
        print(f"| {name} | {total / 1e6:.1f} | {total / base:.3f} | "
              + " | ".join(f"{parts[p] / 1e6:.1f}" for p in PARTS) + " |")
    return 0

PROFILES = {
    "solid": osteon.PrintProfile.solid(),
    "fdm 15 % gyroid": osteon.PrintProfile.fdm(),
    "fdm 0 %": osteon.PrintProfile.fdm(infill=0.0),
    "resin 2 mm": osteon.PrintProfile.resin_hollow(2.0),
}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--instructions", nargs="?", const="", default=None, metavar="OTHER",
                    help="count instructions (callgrind), optionally of another build")
    ap.add_argument("--wall", action="store_true", help="wall time instead of process CPU time")
    ap.add_argument("--threads", type=int, default=None,
                    help="engine threads (default 1; 2 with --wall)")
    args = ap.parse_args(argv)
    if args.instructions is not None:
        return instructions(args.instructions or None)
    import os

    threads = args.threads or (2 if args.wall else 1)
    clock = time.perf_counter if args.wall else time.process_time
    v, f, sk, w = load("cow", subdivisions=1)
    load_before = os.getloadavg()[0]
    times = {name: [] for name in PROFILES}
    for _ in range(args.repeat):
        for name, profile in PROFILES.items():
            t0 = clock()
            a = osteon.analyze(v, f, sk, w, interval=2.0, threads=threads, print_profile=profile)
            times[name].append(clock() - t0)
    base = statistics.median(times["solid"])
    what = "wall time" if args.wall else "CPU time"
    print(f"cow x4: {len(f)} faces, {a.num_sections} sections, h = 2 mm, {threads} thread(s), "
          f"{what}, medians of {args.repeat} interleaved; load {load_before:.1f} -> "
          f"{os.getloadavg()[0]:.1f}")
    print("| profile | median (ms) | ratio to solid |")
    print("|---|---|---|")
    for name, t in times.items():
        m = statistics.median(t)
        print(f"| {name} | {1000 * m:.1f} | {m / base:.3f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
