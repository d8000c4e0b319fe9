"""Property-based fuzzing of the Python API (hypothesis): random meshes, skeletons and weights
must give either a ValueError or a finite, well-formed result (docs/robustness.md).

Bounded for the default run (400 examples per test, about 10 s in total); set the example count
with ``OSTEON_FUZZ_EXAMPLES=5000 pytest tests/python/test_fuzz_api.py`` for a longer search.
"""

from __future__ import annotations

import os

import numpy as np
import osteon
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from shapes import cylinder_along, revolve
from test_robustness import SKIPPED, assert_well_formed


def examples(n: int) -> int:
    return int(os.environ.get("OSTEON_FUZZ_EXAMPLES", n))


FUZZ = settings(max_examples=examples(400), deadline=None, derandomize=False,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])

coord = st.floats(-20, 20, allow_nan=False, allow_infinity=False, width=64)
grid_coord = st.integers(-8, 8).map(float)  # exact coincidences: vertices on planes, flat meshes


@st.composite
def skeletons(draw, max_bones: int = 3, lo: float = -15.0, hi: float = 15.0):
    nb = draw(st.integers(1, max_bones))
    pts = hnp.arrays(np.float64, (nb, 3), elements=st.one_of(
        st.floats(lo, hi, allow_nan=False, width=64), st.integers(int(lo), int(hi)).map(float)))
    heads, tails = draw(pts), draw(pts)
    parents = draw(st.lists(st.integers(-1, nb - 1), min_size=nb, max_size=nb))
    return heads, tails, np.array(parents)


def weights_for(draw, nv: int, nb: int):
    kind = draw(st.sampled_from(["none", "dense", "sparse", "zero_rows"]))
    if kind == "none":
        return None
    w = draw(hnp.arrays(np.float64, (nv, nb), elements=st.sampled_from([0.0, 0.0, 0.25, 1.0])))
    if kind == "zero_rows":
        w[::2] = 0.0
    if kind == "sparse":
        from scipy import sparse

        return sparse.csr_matrix(w)
    return w


def check_or_value_error(call, num_vertices: int):
    """Runs an analysis; a ValueError must name something, anything else must be well formed."""
    try:
        res = call()
    except ValueError as exc:
        assert str(exc)
        return None
    assert_well_formed(res, num_vertices)
    assert ((res.section_flags & SKIPPED) != 0).sum() == (~res.valid).sum()
    assert (res.section_bone >= 0).all() and (res.section_bone < len(res.bone_names)).all()
    assert (res.vertex_bone >= 0).all() and (res.vertex_bone < len(res.bone_names)).all()
    assert 0 <= res.held_bone < len(res.bone_names)
    counted = res.valid & ~res.too_thin  # too-thin sections are reported apart (issue 12)
    if counted.any():
        assert res.max_stress == pytest.approx(np.max(res.stress[counted]))
        np.testing.assert_array_equal(res.weak, counted & (res.stress > res.allowable_stress))
    else:
        assert not res.weak.any() and not res.culled.any()
    return res


@FUZZ
@given(data=st.data())
def test_random_triangles(data):
    nv = data.draw(st.integers(3, 24))
    verts = data.draw(hnp.arrays(np.float64, (nv, 3), elements=st.one_of(coord, grid_coord)))
    nf = data.draw(st.integers(1, 40))
    faces = data.draw(hnp.arrays(np.int64, (nf, 3), elements=st.integers(0, nv - 1)))
    heads, tails, parents = data.draw(skeletons())
    try:
        sk = osteon.Skeleton(heads, tails, parents)
    except ValueError as exc:
        assert any(k in str(exc) for k in ("zero length", "cycle", "own parent", "too long"))
        return
    w = weights_for(data.draw, nv, sk.num_bones)
    interval = data.draw(st.sampled_from([0.5, 1.0, 2.0, 7.0]))
    check_or_value_error(lambda: osteon.analyze(verts, faces, sk, w, interval=interval,
                                                threads=1), nv)


@FUZZ
@given(data=st.data())
def test_random_bad_values_are_value_errors(data):
    """Injected NaN / inf / out-of-range indices always give a ValueError naming them."""
    v, f = revolve(np.linspace(0, 20, 6), np.full(6, 3.0), 8)
    sk = osteon.Skeleton([[1, 0, 0]], [[19, 0, 0]], [-1])
    what = data.draw(st.sampled_from(["nan", "inf", "index", "negative"]))
    v, f = v.copy(), f.astype(np.int64)
    if what in ("nan", "inf"):
        i = data.draw(st.integers(0, len(v) - 1))
        v[i, data.draw(st.integers(0, 2))] = np.nan if what == "nan" else -np.inf
        message = f"vertices contain NaN or infinity \\(row {i}\\)"
    elif what == "index":
        f[data.draw(st.integers(0, len(f) - 1)), data.draw(st.integers(0, 2))] = \
            data.draw(st.integers(len(v), 2**40))
        message = "face index out of range"
    else:
        f[data.draw(st.integers(0, len(f) - 1)), data.draw(st.integers(0, 2))] = \
            data.draw(st.integers(-(2**40), -1))
        message = "negative vertex index"
    with pytest.raises(ValueError, match=message):
        osteon.analyze(v, f, sk)


_BAR = revolve(np.linspace(0, 40, 21), np.full(21, 3.0), 12)
_BAR_SK = osteon.Skeleton([[1, 0, 0], [20, 0, 0]], [[20, 0, 0], [39, 0, 0]], [-1, 0])


@FUZZ
@given(data=st.data())
def test_random_face_subsets_of_closed_mesh(data):
    """Holes of any shape cut into a closed bar: open sections are flagged, never lost."""
    v, f = _BAR
    keep = data.draw(hnp.arrays(np.bool_, len(f), elements=st.booleans()))
    assume(keep.any())
    full = osteon.analyze(v, f, _BAR_SK)
    res = check_or_value_error(lambda: osteon.analyze(v, f[keep], _BAR_SK, threads=1), len(v))
    assert res is not None
    # A section whose plane crosses only kept, intact rings is unchanged; any section that
    # changed carries a flag or still equals the full result.
    changed = ~np.isclose(res.stress, full.stress, rtol=1e-9, equal_nan=True)
    assert (res.section_flags[changed] != 0).all()


@FUZZ
@given(
    radius=st.floats(0.2, 8.0),
    length=st.floats(5.0, 80.0),
    noise=st.floats(0.0, 0.3),
    tilt=st.floats(-0.5, 0.5),
    offset=st.floats(-1.5, 1.5),
    seed=st.integers(0, 2**31 - 1),
    interval=st.sampled_from([0.5, 1.0, 2.0, 3.3]),
    scale=st.sampled_from([1e-3, 1.0, 1e3]),
)
def test_perturbed_primitive(radius, length, noise, tilt, offset, seed, interval, scale):
    rng = np.random.default_rng(seed)
    v, f = cylinder_along([0, 0, 0], [length, 0, 0], radius, n=16, stations=12)
    # Noise relative to the vertex spacing, so the bar stays a (rough) bar rather than a
    # crumpled self-intersecting shell, for which "most sections valid" need not hold.
    spacing = min(2 * np.pi * radius / 16, length / 11)
    v = v + rng.normal(0, noise * spacing, v.shape)
    mid = length / 2
    heads = np.array([[0.05 * length, offset * radius * 0.3, 0], [mid, 0, 0]])
    tails = np.array([[mid, 0, 0], [0.95 * length, tilt * radius, 0]])
    sk = osteon.Skeleton(heads * scale, tails * scale, [-1, 0])
    res = check_or_value_error(
        lambda: osteon.analyze(v * scale, f, sk, interval=interval * scale, threads=1), len(v))
    assert res is not None
    # A noisy closed bar with its bones inside: most sections are computed.
    assert res.valid.mean() > 0.5


@settings(max_examples=examples(40), deadline=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_random_correction_terminates(data):
    v, f = _BAR
    nb = _BAR_SK.num_bones
    w = data.draw(hnp.arrays(np.float64, (len(v), nb), elements=st.sampled_from([0.0, 0.5, 1.0])))
    allowable = data.draw(st.floats(0.5, 40.0))
    max_rounds = data.draw(st.integers(0, 6))
    max_scale = data.draw(st.floats(1.0, 3.0))
    fix = osteon.correct(v, f, _BAR_SK, w, allowable_stress=allowable, max_rounds=max_rounds,
                         max_scale=max_scale, threads=1)
    assert fix.num_rounds <= max_rounds
    assert fix.converged == (not fix.after.weak.any())
    assert fix.reason
    if not fix.converged:
        assert "stay weak" in fix.reason
    assert np.isfinite(fix.vertices).all()
    assert (fix.bone_scale >= 1.0).all() and (fix.bone_scale <= max_scale + 1e-12).all()
    # Vertices without weight never move.
    zero = ~w.any(axis=1)
    np.testing.assert_array_equal(fix.vertices[zero], v[zero])
    assert_well_formed(fix.after, len(v))
