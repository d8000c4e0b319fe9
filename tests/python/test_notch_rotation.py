"""The corner finder does not depend on how the model is turned in space (issue 33, docs/notch.md):
its sectors start where the fillet points themselves say, so a turned model reads the same
corners. Tolerance: Kt and the corner radius to 1e-9 relative, the same flagged sections (the
engine agrees to ~1e-15 here; the turn only rounds the coordinates)."""

from __future__ import annotations

import numpy as np
import osteon
import pytest
from rigged_models import load
from scipy.spatial.transform import Rotation
from test_notch import stepped_bar

TURNS = [(30.0, 50.0, 10.0), (-70.0, 15.0, 120.0)]  # x, y, z Euler angles, degrees
RTOL = 1e-9


def turned(angles, vertices, heads, tails):
    r = Rotation.from_euler("xyz", angles, degrees=True).as_matrix()
    return vertices @ r.T, heads @ r.T, tails @ r.T


def assert_same_corners(a, b):
    assert np.array_equal(a.notch, b.notch)
    assert a.notch.any()  # the test means something only where corners are found
    np.testing.assert_allclose(b.stress_concentration, a.stress_concentration, rtol=RTOL)
    np.testing.assert_allclose(b.notch_radius[a.notch], a.notch_radius[a.notch], rtol=RTOL)
    np.testing.assert_allclose(b.notch_step[a.notch], a.notch_step[a.notch], rtol=RTOL)


@pytest.mark.parametrize("name", ["cheburashka", "arm"])
def test_a_turned_rigged_model_reads_the_same_corners(name):
    # Before the sectors followed the points, the cheburashka turned by (30, 50, 10) read one
    # hand's Kt 4.68 instead of 4.94 and found one more corner; the arm found one more corner
    # (Kt 2.43) in every turn tried.
    v, f, sk, w = load(name)
    heads, tails = np.asarray(sk.heads), np.asarray(sk.tails)
    a = osteon.analyze(v, f, sk, w, interval=2.0)
    for angles in TURNS:
        tv, th, tt = turned(angles, v, heads, tails)
        b = osteon.analyze(tv, f, osteon.Skeleton(th, tt, list(sk.parents)), w, interval=2.0)
        assert_same_corners(a, b)


@pytest.mark.parametrize("rho", [0.6, 0.0])
def test_a_turned_stepped_bar_reads_the_same_corner(rho):
    v, f = stepped_bar(rho)
    heads, tails = np.array([[-15.0, 0, 0]]), np.array([[30.0, 0, 0]])

    def run(vertices, h, t):
        return osteon.analyze(vertices, f, osteon.Skeleton(h, t, [-1]), force=1.0, root=0,
                              min_notch_radius=0.05)

    a = run(v, heads, tails)
    for angles in [(17.0, 0.0, 0.0), *TURNS]:  # about its own axis, then anywhere
        b = run(*turned(angles, v, heads, tails))
        assert_same_corners(a, b)
