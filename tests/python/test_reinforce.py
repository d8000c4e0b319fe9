"""osteon.reinforce: more walls and infill where the printed part is weak (issue 32). Closed
forms from the printed section (docs/printing.md) and the modifier volumes' geometry; meshes made
here. The slicer's side (the G-code of the exported project) is in test_slicer3mf.py."""

from __future__ import annotations

import numpy as np
import osteon
import pytest
import trimesh
from osteon.reinforcement import convex_volume, modifier_volume, weak_regions
from shapes import cylinder_along, merge


def _l_shape():
    """An L: a 40 mm arm r = 4 along +x and a 40 mm post r = 3 rising at its end (bone b)."""
    v, f = merge(cylinder_along((0, 0, 0), (40, 0, 0), 4.0),
                 cylinder_along((40, 0, -4), (40, 0, 40), 3.0))
    sk = osteon.Skeleton([[0, 0, 0], [40, 0, 0]], [[40, 0, 0], [40, 0, 36]], [-1, 0], ["a", "b"])
    return v, f, sk


def _inside(v, f, pts, tol=1e-9):
    """Points inside a closed convex mesh with outward faces (every face plane in front)."""
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    n = np.cross(b - a, c - a)
    return np.all(np.einsum(
        "pfk,fk->pf", pts[:, None, :] - a[None], n) <= tol * np.linalg.norm(n, axis=1), axis=1)


def test_modifier_volume_is_closed_and_encloses_the_weak_span():
    v, f, sk = _l_shape()
    # 14 MPa: the post's lower sections (17.2 .. 14.3 MPa under 10 N) are weak, the arm is not
    a = osteon.analyze(v, f, sk, force=10, allowable_stress=14, interval=2, keep_outlines=True)
    (region,) = weak_regions(a)
    assert set(a.section_bone[region]) == {1}
    assert len(region) == int(a.weak.sum()) >= 3
    mv, mf = modifier_volume(a, region, margin=1.0)
    mesh = trimesh.Trimesh(mv, mf, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume > 0
    inside = np.concatenate([lp for s in region for lp in a.section_loops[s]])
    assert _inside(mv, mf, inside).all()
    # half an interval beyond the end sections along the bone, and the margin around it
    z = a.section_center[region, 2]
    lo, hi = mesh.bounds
    assert lo[2] == pytest.approx(z.min() - 1.0 - 1.0, abs=0.05)
    assert hi[2] == pytest.approx(z.max() + 1.0 + 1.0, abs=0.05)
    assert 2 * (3.0 + 0.92) < hi[0] - lo[0] < 2 * (3.0 + 1.0) + 0.2  # 26 directions: see below
    # the arm beyond one interval + margin from the post is not inside
    arm = np.concatenate([lp for s in np.flatnonzero((a.section_bone == 0)
                                                     & (a.section_param < 34))
                          for lp in a.section_loops[s]])
    assert not _inside(mv, mf, arm).any()


def test_convex_volume_grows_by_the_margin():
    # a 2 mm cube grown by r: V + S r + 6 pi r^2 + 4/3 pi r^3 (Steiner); the 26 growth
    # directions reach at least 0.92 r everywhere, at most r
    cube = np.array([(x, y, z) for x in (0, 2) for y in (0, 2) for z in (0, 2)], float)
    v, f = convex_volume(cube, margin=0.5)
    mesh = trimesh.Trimesh(v, f, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent

    def steiner(r):
        return 8 + 24 * r + 6 * np.pi * r**2 + 4 / 3 * np.pi * r**3

    assert steiner(0.92 * 0.5) < mesh.volume <= steiner(0.5)
    assert _inside(v, f, cube).all()
    assert not _inside(v, f, np.array([[1.0, 1.0, 2.6], [-0.6, 1.0, 1.0]])).any()
