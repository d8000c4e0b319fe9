"""osteon.auto_skeleton on the closed real models with their rigs removed (issue 17).

For each model (120 mm print): bones, time (median of --repeat runs), for each real leaf bone
the distance from its tail to the nearest auto bone end (% of the model size = largest bounding
box side), and the max-stress section with the real rig vs the auto skeleton (20 N, position
distance in % of the model size). Then the skeleton extraction time on the cow subdivided to
~93k faces. Reads ../shared/data (or OSTEON_DATA).

    python bench/bench_autoskeleton.py [--repeat 3] [--models arm cow ...] [--skip-big]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
import osteon
from models import load

MODELS = ["arm", "elephant", "cow", "cheburashka", "rignet2982", "rignet11814"]


def leaf_tails(sk: osteon.Skeleton) -> np.ndarray:
    has_child = np.zeros(sk.num_bones, bool)
    has_child[sk.parents[sk.parents >= 0]] = True
    return sk.tails[~has_child]


def max_stress_point(v, f, sk, w):
    res = osteon.analyze(v, f, sk, w, force=20.0, allowable_stress=60.0, interval=2.0)
    # well-formed sections only (no gap closed, open, outside, ... flag)
    stress = np.where(res.section_flags == 0, np.nan_to_num(res.stress, nan=0.0), 0.0)
    i = int(np.argmax(stress))
    return float(res.stress[i]), res.section_center[i]


def run(name: str, repeat: int) -> dict:
    v, f, real, real_w = load(name)
    size = float(np.ptp(v, axis=0).max())
    times, cpu = [], []
    for _ in range(repeat):
        t, c = time.perf_counter(), time.process_time()
        sk, w = osteon.auto_skeleton(v, f)
        times.append(time.perf_counter() - t)
        cpu.append(time.process_time() - c)
    ends = np.concatenate([sk.heads, sk.tails])
    tips = leaf_tails(real)
    tip_d = np.linalg.norm(tips[:, None] - ends[None], axis=2).min(1) / size * 100
    s_real, c_real = max_stress_point(v, f, real, real_w)
    s_auto, c_auto = max_stress_point(v, f, sk, w)
    return {
        "model": name, "faces": len(f), "real_bones": real.num_bones, "bones": sk.num_bones,
        "time_s": statistics.median(times), "cpu_s": statistics.median(cpu), "real_leaves": len(tips),
        "tip_max_pct": float(tip_d.max()), "tip_median_pct": float(np.median(tip_d)),
        "tips_within_10pct": int((tip_d <= 10).sum()),
        "stress_real": s_real, "stress_auto": s_auto,
        "max_stress_dist_pct": float(np.linalg.norm(c_real - c_auto) / size * 100),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--models", nargs="*", default=MODELS)
    ap.add_argument("--skip-big", action="store_true", help="skip the ~93k-face cow")
    args = ap.parse_args()
    print("| model | faces | real bones | auto bones | time wall / CPU (s) | real leaf tips within 10 % "
          "| tip dist. median / max (% size) | max stress real / auto (MPa) "
          "| max-stress section distance (% size) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name in args.models:
        r = run(name, args.repeat)
        print(f"| {r['model']} | {r['faces']} | {r['real_bones']} | {r['bones']} | "
              f"{r['time_s']:.2f} / {r['cpu_s']:.2f} | {r['tips_within_10pct']}/{r['real_leaves']} | "
              f"{r['tip_median_pct']:.1f} / {r['tip_max_pct']:.1f} | "
              f"{r['stress_real']:.1f} / {r['stress_auto']:.1f} | "
              f"{r['max_stress_dist_pct']:.1f} |", flush=True)
    if not args.skip_big:
        v, f, _, _ = load("cow", subdivisions=1)
        times, cpu = [], []
        for _ in range(args.repeat):
            t, c = time.perf_counter(), time.process_time()
            sk, _w = osteon.auto_skeleton(v, f)
            times.append(time.perf_counter() - t)
            cpu.append(time.process_time() - c)
        print(f"\ncow x4: {len(f)} faces, {sk.num_bones} bones, auto_skeleton median "
              f"{statistics.median(times):.2f} s wall, {statistics.median(cpu):.2f} s CPU over "
              f"{args.repeat} runs")


if __name__ == "__main__":
    main()
