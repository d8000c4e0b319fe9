"""Live mode's moment-arm index and load points (issue 34): a reused Analyzer rebuilds the index
only for the bones whose vertices or frame changed, and asks it again only for sections whose
downstream region holds such a bone; every other section keeps the last run's load point. Its
moment arms and stresses are a one-off analysis's (1e-12 relative)."""

from __future__ import annotations

import numpy as np
import osteon
import pytest
from test_live_grid import assert_close, body_and_arm, posed


@pytest.mark.parametrize("root", [0, 1])
def test_load_points_follow_the_moved_arm_like_one_off_analyses(root):
    # Held at the body's head (root 0): the body's sections carry the arm, whose tip is their
    # farthest point, so they must be asked again when only the arm moves. Held at the arm's
    # head (root 1): the body's sections carry the body alone and keep their load points, the
    # arm's follow it.
    v, f = body_and_arm()
    weights = np.zeros((len(v), 2))
    arm = v[:, 0] > 39.0
    weights[~arm, 0] = weights[arm, 1] = 1.0  # every vertex keeps its bone whatever the pose
    poses = [(0.0, 1.0), (10.0, 1.0), (20.0, 1.0), (20.0, 0.8), (-15.0, 0.8), (-15.0, 0.8)]
    _, sk0 = posed(v, 0.0)
    kw = {"force": 1.0, "interval": 2.0, "root": root}
    an = osteon.Analyzer(f, len(v), sk0, weights, **kw)
    body_arms = []
    for degrees, thin in poses:
        vp, sk = posed(v, degrees, thin=thin)
        live = an.run(vp, sk)
        one_off = osteon.analyze(vp, f, sk, weights, **kw)
        assert_close(live, one_off)
        body = np.asarray(live.section_bone) == 0
        body_arms.append(np.asarray(live.moment_arm, float)[body])
    # Held at the body's head, the body's moment arms follow the arm's tip (a stale load point
    # would keep the straight arm's); held at the arm, they stay bit for bit.
    moved = any(not np.array_equal(body_arms[0], a) for a in body_arms[1:])
    assert moved == (root == 0)


def test_a_live_update_checks_its_moved_vertices_and_recovers():
    # The engine checks the vertices in blocks kept from run to run: a NaN in an update is
    # refused (the first bad row named), and the update after it is a one-off analysis's again.
    v, f = body_and_arm()
    _, sk0 = posed(v, 0.0)
    kw = {"force": 1.0, "interval": 2.0, "root": 0}
    an = osteon.Analyzer(f, len(v), sk0, **kw)
    an.run(*posed(v, 0.0))
    bad, sk = posed(v, 10.0)
    first = int(np.flatnonzero(v[:, 0] > 39.0)[5])
    bad[first, 1] = np.nan
    bad[first + 3, 2] = np.inf
    with pytest.raises(ValueError, match=f"NaN or infinity \\((row|vertex) {first}\\)"):
        an.run(bad, sk)
    vp, sk = posed(v, 20.0)
    assert_close(an.run(vp, sk), osteon.analyze(vp, f, sk, **kw))
