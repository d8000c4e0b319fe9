"""Every number of cow x64 (1.5M faces) analyses, this build against another, byte for byte.

    python bench/identity_x64.py OTHER_PYTHONPATH [--keep DIR]

OTHER_PYTHONPATH: a directory holding another build's ``osteon`` package (as for
compare_builds.py). Each build, in its own child process, analyses cow x64 at h = 2 and 8 mm
with 1 and 2 threads (outlines kept), then runs a live ``Analyzer`` three times: the mesh, then
one leg's vertices moved twice (the moment-arm index keeps the other bones' part, the sections
nothing reaches are reused). Prints how many arrays differ between the builds and, per h,
between 1 and 2 threads of this build; exits 1 on any difference. ~3 minutes per build.
"""

from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent

sys.path.insert(0, str(HERE))
from compare_builds import OTHER_BUILD_IMPORT, both_dumps, other_build_args

CHILD = OTHER_BUILD_IMPORT + """import numpy as np, osteon
from identity_dump import _flatten
from models import load
v, f, sk, w = load("cow", subdivisions=3)
out = {{}}
for h in (2.0, 8.0):
    for t in (1, 2):
        a = osteon.analyze(v, f, sk, w, interval=h, threads=t, keep_outlines=True)
        _flatten(f"x64.h{{h:g}}.t{{t}}", a, out)
bone = np.asarray(w.argmax(axis=1)).ravel()
leg = int(np.argsort(np.bincount(bone, minlength=sk.num_bones))[sk.num_bones // 2])
live = osteon.Analyzer(f, len(v), sk, w, keep_outlines=True)
_flatten("x64.live0", live.run(v), out)
for k, s in enumerate((0.3, 0.6)):
    moved = v.copy()
    moved[bone == leg] += s * np.array([0.5, -0.2, 0.1])
    _flatten(f"x64.live{{k + 1}}", live.run(moved), out)
np.savez({out!r}, **out)
print(osteon.__file__)
"""


def main(argv=None) -> int:
    sys.path.insert(0, str(HERE))
    from identity_dump import compare

    args = other_build_args(__doc__, argv)
    dumps = both_dumps(args.other, args.keep, "x64",
                       lambda out: CHILD.format(here=str(HERE), out=out))
    this, other = dumps["this"], dumps["other"]
    bad = compare(this, other)
    print(f"{len(this)} arrays in this build, {len(other)} in the other; {len(bad)} differ")
    for k in bad[:20]:
        print("  differs:", k)
    threads_bad = 0
    for h in ("2", "8"):
        one = {k[len(f"x64.h{h}.t1"):]: a for k, a in this.items() if k.startswith(f"x64.h{h}.t1")}
        two = {k[len(f"x64.h{h}.t2"):]: a for k, a in this.items() if k.startswith(f"x64.h{h}.t2")}
        n = len(compare(one, two))
        threads_bad += n
        print(f"h = {h} mm: {len(one)} arrays, 1 thread against 2: {n} differ")
    return 1 if bad or threads_bad else 0


if __name__ == "__main__":
    sys.exit(main())
