"""Smoke test of an installed osteon wheel (cibuildwheel's test-command; no test deps):
the compiled engine loads and gives closed-form numbers (mm, mm^2, mm^4, N, MPa).

    python tests/smoke/wheel_smoke.py
"""

import math
import sys

import numpy as np
import osteon


def main() -> int:
    # a 20 x 10 mm rectangle: area b h, second moments b h^3 / 12 and h b^3 / 12
    p = osteon.section_properties([[0, 0], [20, 0], [20, 10], [0, 10]])
    assert p["valid"] and math.isclose(p["area"], 200.0, rel_tol=1e-12), p
    assert np.allclose(sorted(np.asarray(p["second_moment"])[[0, 2]]), [20 * 10**3 / 12,
                                                                        10 * 20**3 / 12]), p
    assert np.allclose(p["centroid"], [10.0, 5.0]), p

    # a 10 x 10 x 100 mm bar along x held at x = 0, 20 N at the far end
    xs = np.linspace(0.0, 100.0, 21)
    ring = np.array([[-5, -5], [5, -5], [5, 5], [-5, 5]], dtype=float)
    verts = np.array([[x, y, z] for x in xs for y, z in ring])
    faces = []
    for k in range(len(xs) - 1):
        for i in range(4):
            a, b, c, d = 4 * k + i, 4 * k + (i + 1) % 4, 4 * (k + 1) + (i + 1) % 4, 4 * (k + 1) + i
            faces += [[a, b, c], [a, c, d]]
    last = 4 * (len(xs) - 1)
    faces += [[0, 2, 1], [0, 3, 2], [last, last + 1, last + 2], [last, last + 2, last + 3]]
    cut = osteon.slice_section(verts, faces, [50, 0, 0], [1, 0, 0])
    assert cut["found"] and len(cut["outer"]) >= 4, cut
    skeleton = osteon.Skeleton([[0, 0, 0]], [[100, 0, 0]], [-1], ["bar"])
    res = osteon.analyze(verts, faces, skeleton, force=20.0, interval=5.0)
    assert res.max_stress > 0 and math.isfinite(res.max_stress), res.max_stress
    # stress = F d / W: the arm d is 80..100 mm near the hold, W >= the square's smallest
    # section modulus a^3 / (6 sqrt 2)
    w_min = 10**3 / (6 * math.sqrt(2))
    assert 20.0 * 80.0 / w_min <= res.max_stress <= 20.0 * 100.0 / w_min * 1.01, res.max_stress
    print(f"osteon {osteon.__version__} ({osteon._core.__file__}): smoke test passed, "
          f"max stress {res.max_stress:.2f} MPa")
    return 0


if __name__ == "__main__":
    sys.exit(main())
