"""The corner search's share of one analysis, in engine instructions (callgrind).

    python bench/bench_notch_cost.py [--model cow --subdivisions 1] [OTHER_PYTHONPATH]

For h = 2 and 8 mm: the instructions of the engine's Analyzer construction and run (threads=1,
as bench/compare_builds.py --instructions counts them) and, from the same run, the inclusive
count of ``osteon::find_notches`` (the corner search, docs/notch.md); prints the search against
the rest of the run (issue 33's budget: at most 0.10 on the ~100k-face cow x4). There is no
option that turns the search off, so its share is read inside the one run. OTHER_PYTHONPATH:
measure another build's ``osteon`` package instead (as compare_builds.py). Needs valgrind.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import tempfile

from compare_builds import HERE, PREAMBLE, callgrind

CHILD = PREAMBLE + """
osteon.analyze(v, f, sk, w, interval={h}, threads=1)
print(osteon.__file__)
"""


def count(other: str | None, model: str, sub: int, h: float) -> tuple[int, int, str]:
    """(instructions of the run, of find_notches within it, osteon's file)."""
    env = dict(os.environ)
    if other:
        env["OSTEON_OTHER_BUILD"] = other
    code = CHILD.format(here=str(HERE), model=model, sub=sub, h=float(h), no_junctions=False)
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "callgrind.out")
        total, stdout = callgrind(code, env, out)
        listing = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", out],
                                 capture_output=True, text=True, check=True).stdout
    notch = next((int(line.split()[0].replace(",", "")) for line in listing.splitlines()
                  if "osteon::find_notches" in line), 0)
    return total, notch, stdout.strip().splitlines()[-1]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("other", nargs="?", help="PYTHONPATH entry of another build's osteon")
    ap.add_argument("--model", default="cow")
    ap.add_argument("--subdivisions", type=int, default=1)
    args = ap.parse_args(argv)
    print("| model | h (mm) | run (M instructions) | corner search (M) | rest (M) | search / rest |")
    print("|---|---|---|---|---|---|")
    for h in (2.0, 8.0):
        total, notch, file = count(args.other, args.model, args.subdivisions, h)
        if args.other and not file.startswith(args.other):
            raise SystemExit(f"the other build was not imported: {file}")
        rest = total - notch
        print(f"| {args.model} x{4 ** args.subdivisions} | {h:g} | {total / 1e6:.1f} | "
              f"{notch / 1e6:.1f} | {rest / 1e6:.1f} | {notch / rest:.3f} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
