"""Live mode's corner reuse (issue 34, cpp/src/notch_reuse.hpp): a live update keeps a corner's
measurement only where no moved triangle reaches its search, and its results are those of
searching every corner again. A live update's face grid depends on the Analyzer's history (its
box has a margin after a rebuild: docs/performance.md), so two Analyzers' updates of the same pose
agree to the order of the sums (1e-12 relative, the rule for live updates), not bit for bit."""

from __future__ import annotations

import numpy as np
import osteon
from shapes import revolve

CORNER_FIELDS = ("stress_concentration", "notch_radius", "notch_step", "stress",
                 "nominal_stress", "max_stress")


def two_step_bar(rho_left: float, rho_right: float, arc: int = 9):
    """Closed round bar along x (mm): thick (diameter 12) for x in [-10, 10], thin (diameter 6)
    beyond on both sides out to +-40, a shoulder fillet of radius rho_left at x = -10 and
    rho_right at x = +10 (the same vertex count for any radii)."""
    th = np.linspace(0.0, np.pi / 2, arc)
    right_x = list(10.0 + rho_right - rho_right * np.cos(th))
    right_t = list(3.0 + rho_right - rho_right * np.sin(th))
    tail = np.linspace(11.5, 40.0, 58)  # the same stations for any radius up to 1 mm
    xs_r = [10.0] + right_x + list(tail)
    ts_r = [6.0] + right_t + [3.0] * len(tail)
    left_x = [-x for x in (10.0 + rho_left - rho_left * np.cos(th))]
    left_t = list(3.0 + rho_left - rho_left * np.sin(th))
    head = -tail[::-1]
    xs = list(head) + left_x[::-1] + [-10.0] + list(np.arange(-9.0, 10.0, 1.0)) + xs_r
    ts = [3.0] * len(head) + left_t[::-1] + [6.0] * 20 + ts_r
    return revolve(xs, ts, 96)


def skeleton():
    # held at the middle: one bone out to each end
    return osteon.Skeleton(np.array([[0.0, 0, 0], [0.0, 0, 0]]),
                           np.array([[-40.0, 0, 0], [40.0, 0, 0]]), [-1, 0])


def fresh(v, f):
    return osteon.analyze(v, f, skeleton(), force=1.0, interval=2.0, root=0)


def analyzer(f, n):
    return osteon.Analyzer(f, n, skeleton(), force=1.0, interval=2.0, root=0)


def searched_again(v, f):
    """A live update of `v` after one in which every vertex moved: every section cut and every
    corner searched anew (in the live update's face order), nothing reused."""
    an = analyzer(f, len(v))
    an.run(v)
    an.run(v * 1.001)
    return an.run(v)


def assert_same(a, b):
    """Within 1e-12 relative (of each field's largest value): a stale corner (a fillet measured
    before it moved) is off by ~5 % of its Kt."""
    for name in CORNER_FIELDS + ("section_area", "section_modulus", "moment_arm"):
        x, y = (np.atleast_1d(np.asarray(getattr(r, name), float)) for r in (a, b))
        assert x.shape == y.shape, name
        scale = np.nanmax(np.abs(y)) if y.size else 0.0
        np.testing.assert_allclose(x, y, rtol=1e-12, atol=1e-12 * scale, err_msg=name)


def assert_same_bits(a, b):
    for name in CORNER_FIELDS + ("section_area", "section_modulus", "moment_arm"):
        x, y = (np.atleast_1d(np.asarray(getattr(r, name), float)) for r in (a, b))
        assert x.shape == y.shape and np.array_equal(x.view(np.uint8), y.view(np.uint8)), name


def test_a_moved_fillet_is_measured_again_and_an_untouched_one_reused_exactly():
    v0, f = two_step_bar(0.5, 0.5)
    v1, f1 = two_step_bar(0.5, 1.0)   # the right fillet widens; the left one does not move
    assert np.array_equal(f, f1)
    a0, a1 = fresh(v0, f), fresh(v1, f)
    corners0 = np.flatnonzero(a0.stress_concentration > 1)
    corners1 = np.flatnonzero(a1.stress_concentration > 1)
    assert len(corners0) == 2 and np.array_equal(corners0, corners1)
    # The sections (and so each corner's search inputs) are the same: only the fillet's mesh
    # says the right corner changed (a reuse keyed on the sections alone would keep it stale).
    assert np.array_equal(a0.section_area, a1.section_area)
    assert np.array_equal(a0.moment_arm, a1.moment_arm)
    kt0, kt1 = a0.stress_concentration[corners0], a1.stress_concentration[corners0]
    right = np.argmax(a0.section_center[corners0, 0])
    assert kt1[right] < kt0[right] - 0.05          # a wider fillet: a lower Kt (Peterson)
    assert kt1[1 - right] == kt0[1 - right]
    # A one-off analysis and the first run of an Analyzer take the faces in the grid's order;
    # live updates in their own order (notch_reuse.hpp): the same corners to ~1e-15.
    an = analyzer(f, len(v0))
    assert_same_bits(an.run(v0), a0)
    ref = {0: searched_again(v0, f), 1: searched_again(v1, f)}
    for k in (1, 0, 0, 1, 1, 0):
        a = an.run((v0, v1)[k])
        assert_same(a, ref[k])
        np.testing.assert_allclose(a.stress_concentration, (a0, a1)[k].stress_concentration,
                                   rtol=1e-13)


def test_a_move_far_from_the_corners_keeps_them_whatever_the_grid():
    # The bar's thin ends stretch: the model's box (and so the face grid's cells) changes, the
    # corners' regions do not; their measurement must not depend on the grid's layout, and the
    # stretched ends' sections must be cut through the moved faces' new cells.
    v0, f = two_step_bar(0.5, 0.8)
    an = analyzer(f, len(v0))
    an.run(v0)
    for k in (1, 2, 3, 2):
        v = v0.copy()
        far = np.abs(v[:, 0]) > 36.0
        v[far, 0] *= 1.0 + 0.03 * k  # the tips move 1.2 mm per step (cells ~0.8 mm)
        assert_same(an.run(v), searched_again(v, f))
