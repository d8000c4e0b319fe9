"""The engine's quadric edge-collapse decimation (issue 35: auto_skeleton's first pass on meshes
of more than 30 k faces): the face count reached, a closed consistently oriented 2-manifold of
the same genus kept, the vertices on the original surface (closed form of a torus), the same
output for the same input."""

import numpy as np
import osteon
import pytest
from osteon import _core
from osteon.autoskeleton import END_RATIO, curve
from shapes import revolve, torus


def edges(f):
    """(directed edges (3F,2), undirected edges (E,2) each once, faces per undirected edge)."""
    directed = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    undirected, count = np.unique(np.sort(directed, axis=1), axis=0, return_counts=True)
    return directed, undirected, count


def test_torus_decimated_to_the_target_stays_a_closed_torus_on_its_surface():
    R, r = 30.0, 8.0
    v, f = torus(R, r, n=192, m=64)
    target = 2000
    dv, df = _core.decimate_mesh(v, f, target)
    # every collapse of an interior edge removes exactly two faces: an even target is reached
    assert len(df) == target
    directed, undirected, count = edges(df)
    assert np.all(count == 2)  # closed 2-manifold: every edge between exactly two faces
    assert len(np.unique(directed, axis=0)) == len(directed)  # consistently oriented
    assert len(dv) - len(undirected) + len(df) == 0  # Euler characteristic: still genus 1
    assert len(np.unique(df)) == len(dv)  # no vertex left out of the faces
    # vertices on the torus: |distance to the tube's centre circle - r| is the distance to the
    # surface; a collapsed vertex lies within an edge's sagitta on the tube's curvature
    ring = np.hypot(dv[:, 0], dv[:, 1]) - R
    off = np.abs(np.hypot(ring, dv[:, 2]) - r)
    e = np.linalg.norm(dv[undirected[:, 0]] - dv[undirected[:, 1]], axis=1)
    assert off.max() < np.median(e) ** 2 / (8 * r), (off.max(), np.median(e))
    # faces still face outward (away from the tube's centre circle)
    c = dv[df].mean(1)
    n = np.cross(dv[df[:, 1]] - dv[df[:, 0]], dv[df[:, 2]] - dv[df[:, 0]])
    axis_pt = np.column_stack([c[:, 0], c[:, 1], np.zeros(len(c))])
    axis_pt *= (R / np.hypot(c[:, 0], c[:, 1]))[:, None]
    assert np.all(np.einsum("ij,ij->i", n, c - axis_pt) > 0)
    # the same input gives the same output, bit for bit
    dv2, df2 = _core.decimate_mesh(v, f, target)
    assert np.array_equal(dv, dv2) and np.array_equal(df, df2)


def test_a_tetrahedron_is_not_collapsed_and_bad_input_is_a_value_error():
    v = np.array([[0, 0, 0], [10, 0, 0], [0, 10, 0], [0, 0, 10]], float)
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], np.int32)
    dv, df = _core.decimate_mesh(v, f, 0)
    assert len(df) == 4 and np.array_equal(dv, v)  # the smallest closed mesh stays
    with pytest.raises(ValueError, match="range"):
        _core.decimate_mesh(v, np.array([[0, 1, 9]], np.int32), 1)
    with pytest.raises(ValueError, match="target"):
        _core.decimate_mesh(v, f, -1)


def test_a_finely_tessellated_capsule_is_predecimated_and_keeps_its_bones():
    """A capsule of 48 k faces (over PRE_DECIMATE_ABOVE) is decimated to PRE_FACES before the
    skeleton; its chain still ends END_RATIO radii inside each tip (the closed form of
    test_autoskeleton's capsule) on the axis."""
    length, radius = 80.0, 6.0
    a = np.linspace(np.pi / 2, 0, 17)[:-1]
    xs0, r0 = -radius * np.sin(a), radius * np.cos(a)
    xs = np.r_[xs0, np.linspace(0, length, 120), length - xs0[::-1]]
    rs = np.r_[r0, np.full(120, radius), r0[::-1]]
    rs[0] = rs[-1] = radius * 0.05
    v, f = revolve(xs, rs, 160)
    assert len(f) > curve.PRE_DECIMATE_ABOVE
    _dv, df = curve.predecimate(v, f)
    assert len(df) == curve.PRE_FACES
    sk, w = osteon.auto_skeleton(v, f)
    assert w.shape == (len(v), sk.num_bones)
    ends = np.concatenate([sk.heads, sk.tails])
    assert np.abs(ends[:, 1:]).max() < 1.0  # on the axis
    inset = END_RATIO * radius
    assert ends[:, 0].min() == pytest.approx(-radius + inset, abs=1.0)
    assert ends[:, 0].max() == pytest.approx(length + radius - inset, abs=1.0)
