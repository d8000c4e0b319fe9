"""Cost per section as the section count grows (issue 20): it must stay flat.

    python bench/bench_section_scaling.py [--model cow] [--repeat 5] [--counts 1000 10000 100000]
        [--cancel]

The same rigged model is printed bigger and bigger at h = 2 mm, so that the analysis makes
about 1k, 10k, 100k sections (``osteon.estimate_sections`` picks the print size; it is exact).
For each size: the median time of ``osteon.analyze`` (one worker thread, so that the machine's
load does not blur the shape), of the report the front ends build from it
(``osteon.report.build_report``), and of ``estimate_sections`` itself; microseconds per section
and the ratio to the smallest count's cost per section (1.0 = flat). A cost that grows faster
than the section count shows as a ratio that climbs with the count (before the fix of issue 20
the moment arms made the ratio ~1.5 at 50k sections and hours at millions).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import osteon
from models import load, median_time
from osteon import report


def size_for(sk, target: int, h: float) -> float:
    """Print height (mm, of a model loaded at 120 mm) giving about ``target`` sections."""
    lo, hi = 1.0, 1e7
    for _ in range(60):
        mid = (lo * hi) ** 0.5
        if osteon.estimate_sections(sk.scaled(mid / 120.0), h) < target:
            lo = mid
        else:
            hi = mid
    return hi


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default="cow")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--counts", type=int, nargs="+", default=[1000, 10_000, 100_000])
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--cancel", action="store_true",
                    help="also time Progress.cancel() -> Cancelled at the largest count")
    args = ap.parse_args(argv)
    h = 2.0
    v, f, sk, w = load(args.model, height_mm=120.0)
    print(f"{args.model}: {len(v)} vertices, {len(f)} faces, {sk.num_bones} bones; h = {h:g} mm, "
          f"threads = {args.threads}, medians of {args.repeat}")
    print("| sections | print height (mm) | analyze median (ms) | us / section | ratio | "
          "report median (ms) | us / section | ratio | estimate (us) |")
    print("|---|---|---|---|---|---|---|---|---|")
    base = None
    for target in args.counts:
        size = size_for(sk, target, h)
        k = size / 120.0
        vk, skk = v * k, sk.scaled(k)
        holder = {}

        def run(vk=vk, skk=skk, holder=holder):
            holder["a"] = osteon.analyze(vk, f, skk, w, interval=h, threads=args.threads,
                                         keep_outlines=True)

        t_an = median_time(run, args.repeat)
        a = holder["a"]

        def rep(a=a):
            report.build_report(analysis=a, bone_names=sk.names, allowable_mpa=30.0,
                                settings={}, front_end="bench", model=args.model)

        t_rep = median_time(rep, args.repeat)
        t0 = time.perf_counter()
        for _ in range(100):
            osteon.estimate_sections(skk, h)
        t_est = (time.perf_counter() - t0) / 100
        n = a.num_sections
        per_an, per_rep = t_an / n * 1e6, t_rep / n * 1e6
        if base is None:
            base = (per_an, per_rep)
        print(f"| {n} | {size:.0f} | {t_an * 1e3:.1f} | {per_an:.1f} | {per_an / base[0]:.2f} | "
              f"{t_rep * 1e3:.1f} | {per_rep:.1f} | {per_rep / base[1]:.2f} | {t_est * 1e6:.0f} |",
              flush=True)
    if args.cancel:
        cancel_latency(v, f, sk, w, h, args)
    return 0


def cancel_latency(v, f, sk, w, h, args) -> None:
    """Median time from ``Progress.cancel()`` (another thread, at 30 % of the sections of the
    largest count) to the analysis raising ``Cancelled``: the engine's share of Esc in Blender."""
    import statistics
    import threading

    k = size_for(sk, args.counts[-1], h) / 120.0
    vk, skk = v * k, sk.scaled(k)
    total = osteon.estimate_sections(skk, h)
    stops = []
    for _ in range(args.repeat):
        p = osteon.Progress()
        out = {}

        def work(p=p, out=out):
            try:
                osteon.analyze(vk, f, skk, w, interval=h, threads=args.threads,
                               keep_outlines=True, progress=p)
            except osteon.Cancelled:
                out["end"] = time.perf_counter()

        t = threading.Thread(target=work)
        t.start()
        while p.sections_done < 0.3 * total and t.is_alive():
            time.sleep(0.001)
        t0 = time.perf_counter()
        p.cancel()
        t.join()
        stops.append(out["end"] - t0)
    print(f"cancel at 30 % of {total} sections: stopped after a median "
          f"{statistics.median(stops) * 1e3:.2f} ms ({[round(x * 1e3, 2) for x in stops]})")


if __name__ == "__main__":
    sys.exit(main())
