"""This build of osteon against another build, in alternating child processes.

    python bench/compare_builds.py OTHER_PYTHONPATH [--rounds 7] [--model cow --subdivisions 1]
        [--cpu] [--no-junctions] [--instructions] [--identity [--keep DIR]]

OTHER_PYTHONPATH is a directory holding another build's ``osteon`` package (its
``python/osteon`` directory with its compiled ``_core`` module inside). Two pybind11 builds
cannot share one process (their types clash), so each round runs one child process per build,
back to back (the order alternates), each timing 3 analyses after a warm-up; machine load then
hits both builds alike (``--cpu``: one thread, process CPU time; ``--no-junctions``: this build
runs with ``junctions=False``, for a baseline built before the junction stage existed). Prints, per interval h, the median time (ms) of each build over all
rounds and the ratio this build / other build.

``--instructions``: instead of times, the machine instructions the engine executes for one
analysis (its ``Analyzer`` construction and run, counted by valgrind's callgrind; needs
``valgrind``, e.g. ``apt-get install valgrind``). Exact and repeatable to the instruction,
whatever the machine's load: the figure to compare on a noisy machine (the VM has no hardware
counters for ``perf stat``). One analysis per h in its own child process per build.

``--identity``: instead of times, every number of the analyses of bench/identity_dump.py (all
real models of tests/data, outlines, junctions on and off, live runs, loose pieces, a
correction), one child process per build, compared byte for byte; exits 1 on any difference
(``--keep DIR`` keeps both dumps as .npz) and prints, per array kind (result field), the largest
relative difference among the differing arrays (inf: a count, flag, shape or NaN differs, not
the last bits). A one-off analysis may differ from main's in the last bits (the team's rule,
docs/performance.md); anything above 1e-9 relative is to be explained.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent

# Every child: the other build (OSTEON_OTHER_BUILD) imported instead of this one, and bench/ on
# the path. Shared by compare_corners.py.
OTHER_BUILD_IMPORT = """
import os, sys
if os.environ.get("OSTEON_OTHER_BUILD"):
    # An editable install's import redirect would win over PYTHONPATH: drop it.
    sys.meta_path = [f for f in sys.meta_path if "Redirecting" not in type(f).__name__]
    sys.path.insert(0, os.environ["OSTEON_OTHER_BUILD"])
sys.path.insert(0, {here!r})
"""

# The timing and instruction children: that, the model, the keywords.
PREAMBLE = OTHER_BUILD_IMPORT + """import osteon
from models import load
v, f, sk, w = load({model!r}, subdivisions={sub})
kw = {{"junctions": False}} if {no_junctions} and not os.environ.get("OSTEON_OTHER_BUILD") else {{}}
"""

CHILD = PREAMBLE + """
import json, time
out = {{}}
for h in (2.0, 8.0):
    osteon.analyze(v, f, sk, w, interval=h, threads={threads}, **kw)
    ts = []
    for _ in range(3):
        t0 = {clock}()
        osteon.analyze(v, f, sk, w, interval=h, threads={threads}, **kw)
        ts.append({clock}() - t0)
    out[str(h)] = ts
print(json.dumps({{"faces": len(f), "times": out, "file": osteon.__file__}}))
"""


def run_child(pythonpath: str | None, model: str, sub: int, cpu: bool,
              no_junctions: bool = False) -> dict:
    env = dict(os.environ)
    if pythonpath:
        env["OSTEON_OTHER_BUILD"] = pythonpath
    code = CHILD.format(here=str(HERE), model=model, sub=sub, threads=1 if cpu else 0,
                        clock="time.process_time" if cpu else "time.perf_counter",
                        no_junctions=no_junctions)
    res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         check=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


INSTRUCTIONS_CHILD = PREAMBLE + """
osteon.analyze(v, f, sk, w, interval={h}, threads=1, **kw)
print(len(f), osteon.__file__)
"""


def callgrind(code: str, env: dict, out: str) -> tuple[int, str]:
    """Runs `code` in a child Python under callgrind, counting the engine's Analyzer
    construction and run into the file `out`: (instructions counted, the child's stdout)."""
    res = subprocess.run(
        ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
         "--toggle-collect=osteon::Analyzer::Analyzer*",
         "--toggle-collect=osteon::Analyzer::Impl::run*", sys.executable, "-c", code],
        env=env, capture_output=True, text=True, check=True)
    with open(out) as fh:
        total = next(int(line.split()[1]) for line in fh if line.startswith("totals:"))
    return total, res.stdout


def count_instructions(pythonpath: str | None, model: str, sub: int, h: float,
                       no_junctions: bool) -> tuple[int, int, str]:
    """(instructions in the engine's Analyzer construction + run, faces, osteon's file)."""
    import tempfile

    env = dict(os.environ)
    if pythonpath:
        env["OSTEON_OTHER_BUILD"] = pythonpath
    code = INSTRUCTIONS_CHILD.format(here=str(HERE), model=model, sub=sub, h=float(h),
                                     no_junctions=no_junctions)
    with tempfile.TemporaryDirectory() as tmp:
        total, stdout = callgrind(code, env, os.path.join(tmp, "callgrind.out"))
    faces, file = stdout.strip().splitlines()[-1].split(" ", 1)
    return total, int(faces), file


IDENTITY_CHILD = OTHER_BUILD_IMPORT + """import numpy as np, osteon, identity_dump
np.savez({out!r}, **identity_dump.dump())
print(osteon.__file__)
"""


def child_arrays(code: str, other: str | None, out: str) -> dict:
    """The arrays a child process saves to `out` (.npz) running `code` (which starts with
    OTHER_BUILD_IMPORT and prints osteon's file last), with the other build imported when
    `other` is given (checked: exits if that build was not the one imported). both_dumps runs it for
    both builds."""
    import numpy as np

    env = dict(os.environ)
    if other:
        env["OSTEON_OTHER_BUILD"] = other
    res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         check=True)
    file = res.stdout.strip().splitlines()[-1]
    if other and not file.startswith(other):
        raise SystemExit(f"the other build was not imported: {file}")
    with np.load(out) as data:
        return {k: data[k] for k in data.files}


def both_dumps(other: str, keep: str | None, prefix: str, code_for) -> dict:
    """{"this": arrays, "other": arrays}: `code_for(out)` (a child's code saving to `out`) run
    by child_arrays with this build and with `other`, the .npz files in `keep` (kept) or a
    temporary folder (removed)."""
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(keep or tmp)
        folder.mkdir(parents=True, exist_ok=True)
        dumps = {}
        for name, path in (("this", None), ("other", other)):
            out = str(folder / f"{prefix}_{name}.npz")
            dumps[name] = child_arrays(code_for(out), path, out)
    return dumps


def other_build_args(doc: str, argv=None) -> argparse.Namespace:
    """The command line of the scripts that compare this build with another: OTHER, --keep."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("other", help="PYTHONPATH entry holding the other build's osteon package")
    ap.add_argument("--keep", help="keep both dumps (.npz) in this folder")
    return ap.parse_args(argv)


def identity(other: str, keep: str | None) -> int:
    """Both builds' identity dumps compared byte for byte: 0 when every array is equal."""
    from identity_dump import compare, largest_relative

    dumps = both_dumps(other, keep, "identity",
                       lambda out: IDENTITY_CHILD.format(here=str(HERE), out=out))
    bad = compare(dumps["this"], dumps["other"])
    values = sum(a.size for a in dumps["this"].values())
    print(f"{len(dumps['this'])} arrays ({values} numbers) in this build, "
          f"{len(dumps['other'])} in the other; {len(bad)} differ")
    for k in bad[:50]:
        print("  differs:", k)
    if bad:
        print("largest relative difference per array kind (inf: not a rounding difference):")
        worst = largest_relative(dumps["this"], dumps["other"], bad)
        for kind, (rel, name) in sorted(worst.items(), key=lambda item: -item[1][0]):
            print(f"  {kind:32s} {rel:.3g}  ({name})")
    return 1 if bad else 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("other", help="PYTHONPATH entry holding the other build's osteon package")
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--model", default="cow")
    ap.add_argument("--subdivisions", type=int, default=1)
    ap.add_argument("--cpu", action="store_true",
                    help="one thread, CPU time (steadier than wall time on a loaded machine)")
    ap.add_argument("--no-junctions", action="store_true",
                    help="this build without the junction stage (analyze(junctions=False))")
    ap.add_argument("--instructions", action="store_true",
                    help="count the engine's instructions (callgrind) instead of timing")
    ap.add_argument("--identity", action="store_true",
                    help="compare every number of bench/identity_dump.py byte for byte")
    ap.add_argument("--keep", help="with --identity: keep both dumps (.npz) in this folder")
    args = ap.parse_args(argv)
    if args.identity:
        return identity(args.other, args.keep)
    if args.instructions:
        print("| model | faces | h (mm) | this build (M instructions) | other build "
              "(M instructions) | ratio |")
        print("|---|---|---|---|---|---|")
        for h in (2.0, 8.0):
            a, faces, _ = count_instructions(None, args.model, args.subdivisions, h,
                                             args.no_junctions)
            b, _, file = count_instructions(args.other, args.model, args.subdivisions, h,
                                            args.no_junctions)
            if not file.startswith(args.other):
                raise SystemExit(f"the other build was not imported: {file}")
            print(f"| {args.model} x{4 ** args.subdivisions} | {faces} | {h:g} | {a / 1e6:.1f} | "
                  f"{b / 1e6:.1f} | {a / b:.3f} |")
        return 0
    times = {"this": {}, "other": {}}
    faces = 0
    for r in range(args.rounds):
        order = [("this", None), ("other", args.other)]
        if r % 2:
            order.reverse()
        for name, path in order:
            out = run_child(path, args.model, args.subdivisions, args.cpu, args.no_junctions)
            faces = out["faces"]
            if path and not out["file"].startswith(path):
                raise SystemExit(f"the other build was not imported: {out['file']}")
            for h, ts in out["times"].items():
                times[name].setdefault(h, []).extend(ts)
    print("| model | faces | h (mm) | this build median (ms) | other build median (ms) | ratio |")
    print("|---|---|---|---|---|---|")
    for h in times["this"]:
        a = statistics.median(times["this"][h]) * 1e3
        b = statistics.median(times["other"][h]) * 1e3
        print(f"| {args.model} x{4 ** args.subdivisions} | {faces} | {float(h):g} | {a:.2f} | "
              f"{b:.2f} | {a / b:.3f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
