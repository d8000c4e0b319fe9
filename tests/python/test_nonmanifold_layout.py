"""Whole-plane cuts of non-manifold sections do not depend on the face grid's layout (issue 34).
Where a mesh edge carries more than two cut endpoints (a non-manifold section), which endpoint
pairs with which used to follow the order the grid's cells handed the segments over, so a one-off
analysis changed when only the grid's box changed (one tiny far triangle added: RigNet 17872's
section 10, cut area 867.1 against 845.5 mm²), and a live update (grid kept from the last pose)
disagreed with a one-off analysis of the same pose. The crowded cuts are now paired in a canonical
order of the segments (by their edges, orientation and points). Likewise a loop of an
inconsistently wound surface (RigNet 17872 and 15446 have faces turned over) used to run in the
direction of the segment the walk began with; it now runs the way most of its segments do."""

from __future__ import annotations

import numpy as np
import osteon
import pytest
from osteon.io import load_model
from rigged_models import DATA
from scipy import sparse

SECTION_FIELDS = ("section_area", "section_modulus", "section_cut_area", "section_flags",
                  "section_center")
FIELDS = SECTION_FIELDS + ("stress", "moment_arm")
NON_MANIFOLD = 64  # SectionFlag non_manifold


def _model(number: int):
    m = load_model(DATA / f"RigNet/{number}_ori.obj")
    v = np.asarray(m.vertices, float)
    return v, np.asarray(m.faces, np.int32), m.skeleton, m.weights


def _moved(v):
    return v + 0.01 * np.sin(v[:, [1, 2, 0]])


def _differing(a, b, fields=FIELDS, rel=0.0):
    out = []
    for name in fields:
        x, y = (np.asarray(getattr(r, name), float) for r in (a, b))
        assert x.shape == y.shape, name
        if rel == 0.0:
            if x.tobytes() != y.tobytes():
                out.append(name)
        elif not np.allclose(x, y, rtol=rel, atol=0.0, equal_nan=True):
            out.append(name)
    return out


def test_a_far_triangle_that_only_widens_the_grid_changes_no_whole_cut():
    v, f, sk, w = _model(17872)
    v = _moved(v)
    # The gap tolerance fixed: by default it is 1 % of the mesh's diagonal, which the far
    # triangle lengthens.
    gap = 0.01 * float(np.linalg.norm(np.ptp(v, axis=0)))
    kw = {"threads": 1, "junctions": False, "local_cuts": False, "gap_tolerance": gap}
    a = osteon.analyze(v, f, sk, w, **kw)
    # the whole cuts cross non-manifold edges: the case the pairing's order decides
    assert (np.asarray(a.section_flags) & NON_MANIFOLD).sum() >= 8
    lo, hi = v.min(0), v.max(0)
    corner = hi + 0.2 * (hi - lo)  # far from every bone: no section's plane reaches it
    far = np.array([corner, corner + [0.1, 0, 0], corner + [0, 0.1, 0]])
    vv = np.vstack([v, far])
    ff = np.vstack([f, [[len(v), len(v) + 1, len(v) + 2]]]).astype(np.int32)
    far_weights = sparse.csr_matrix(([1.0] * 3, ([0, 1, 2], [0] * 3)), shape=(3, w.shape[1]))
    ww = sparse.vstack([sparse.csr_matrix(w), far_weights]).tocsr()
    b = osteon.analyze(vv, ff, sk, ww, **kw)
    # The sections (not the stresses: the far triangle's weight is a load on bone 0)
    assert _differing(a, b, SECTION_FIELDS) == []


@pytest.mark.parametrize("number", [17872, 15446])
def test_a_live_update_of_a_fully_moved_pose_is_its_one_off_analysis(number):
    # Every vertex moves: the live grid is rebuilt on the pose's box widened by 5 %, unlike a
    # one-off analysis's grid over the moved mesh's own box (fails when the loops follow the
    # cells' order).
    v, f, sk, w = _model(number)
    live = osteon.Analyzer(f, len(v), sk, w, threads=1)
    live.run(v)
    moved = _moved(v)
    a = live.run(moved)
    b = osteon.analyze(moved, f, sk, w, threads=1)
    assert _differing(a, b, FIELDS, rel=1e-12) == []
    assert np.array_equal(np.asarray(a.section_flags), np.asarray(b.section_flags))
