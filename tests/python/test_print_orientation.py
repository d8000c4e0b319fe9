"""best_orientation with a print profile (issue 31): the printed section turns with the build
direction, so the best candidates are analysed again with the profile and re-ranked. On a
generated L-shaped rod (no shared data)."""

from __future__ import annotations

import dataclasses

import numpy as np
import osteon
import pytest
from osteon import orientation
from shapes import cylinder_along, merge


@pytest.fixture(scope="module")
def l_rod():
    """L rod: 60 mm along x, then 40 mm up along z (r = 4 mm), two bones."""
    v, f = merge(cylinder_along([0, 0, 0], [60, 0, 0], 4.0),
                 cylinder_along([60, 0, 0], [60, 0, 40], 4.0))
    sk = osteon.Skeleton([[0, 0, 0], [60, 0, 0]], [[60, 0, 0], [60, 0, 40]], [-1, 0])
    return v, f, sk


def test_rescoring_keeps_the_direction_its_own_analysis_ranks_best(l_rod, monkeypatch):
    """The re-analysis decides, not the sphere search: a stand-in engine whose printed stress
    grows with the build direction's z (a part weakest when stood up) makes the printed ranking
    differ from the isotropic one (where every direction ties)."""
    v, f, sk = l_rod
    real = osteon._api.analyze
    calls = []

    def printed_stand_in(*args, print_profile=None, build_direction=(0, 0, 1), **kw):
        assert print_profile == osteon.profiles.get_profile("prusaslicer")
        d = np.asarray(build_direction, float)
        calls.append(d / np.linalg.norm(d))
        a = real(*args, build_direction=d, **kw)
        return dataclasses.replace(a, stress=a.stress * (1.0 + abs(d[2]) / np.linalg.norm(d)))

    monkeypatch.setattr(osteon._api, "analyze", printed_stand_in)
    base = real(v, f, sk, interval=4.0)
    o = osteon.best_orientation(base, samples=200, print_profile="prusaslicer",
                                model=(v, f, sk, None), rescore=3)
    dirs = np.array(calls)
    assert 4 <= len(dirs) <= 3 + 4  # the best three, the current direction and the axes
    for axis in np.eye(3):  # every axis analysed (the current +Z among them)
        assert (np.abs(dirs @ axis) > 1 - 1e-9).any()
    assert abs(o.direction[2]) < 1e-6  # stood up is the weakest; lying wins
    assert o.worst_ratio == pytest.approx(base.max_stress / base.allowable_stress, rel=1e-9)
    assert o.reference_ratio == pytest.approx(2 * o.worst_ratio, rel=1e-9)  # +Z: twice
    assert all(c["worst_ratio"] >= c["search_ratio"] * (1 - 1e-12) for c in o.candidates)


def test_a_profile_needs_the_model(l_rod):
    v, f, sk = l_rod
    a = osteon.analyze(v, f, sk, interval=4.0)
    with pytest.raises(ValueError, match="needs model"):
        osteon.best_orientation(a, samples=50, print_profile="cura")
    # solid: the search alone, no model needed, the same result as without a profile
    assert np.array_equal(osteon.best_orientation(a, samples=50, print_profile="solid").direction,
                          osteon.best_orientation(a, samples=50).direction)
    assert not orientation._printed(None) and orientation._printed("cura")


def test_printed_orientation_on_the_real_engine(l_rod):
    v, f, sk = l_rod
    a = osteon.analyze(v, f, sk, interval=4.0, layer_strength_ratio=0.55)
    o = osteon.best_orientation(a, samples=500, print_profile="prusaslicer",
                                model=(v, f, sk, None), rescore=3)
    # printed sections are never stronger than solid ones, and the best is at most the current
    assert all(c["worst_ratio"] >= c["search_ratio"] * (1 - 1e-9) for c in o.candidates)
    assert o.worst_ratio <= o.reference_ratio * (1 + 1e-9)
