"""Every closed rigged model of tests/data analyses with finite results (docs/method.md, Targets)."""

import numpy as np
import osteon
import pytest
from rigged_models import load

CLOSED = ["elephant", "arm", "cheburashka", "cow", "rignet2982", "rignet11814"]


@pytest.fixture(scope="module", params=CLOSED)
def model(request, data_dir):
    return request.param, load(request.param, height_mm=120.0)


def test_closed_models_give_finite_results(model):
    name, (v, f, sk, w) = model
    res = osteon.analyze(v, f, sk, w, force=20.0, allowable_stress=60.0, interval=2.0)
    assert res.num_sections > 20
    valid = res.valid
    # closed single-piece meshes: (almost) every section is computed
    assert valid.mean() > 0.95, (name, [res.flag_names(i) for i in np.flatnonzero(~valid)])
    assert np.all(np.isfinite(res.section_modulus[valid])) and np.all(res.section_modulus[valid] > 0)
    assert np.all(np.isfinite(res.stress[valid])) and np.all(res.stress[valid] >= 0)
    assert np.all(np.isfinite(res.vertex_stress)) and len(res.vertex_stress) == len(v)
    # vertices interpolate between sections: never above the largest section stress
    assert res.vertex_stress.max() <= np.nanmax(res.stress) * (1 + 1e-12)
    assert res.vertex_stress.min() >= 0
    assert res.max_stress > 0
    # W_k culling is consistent
    assert not np.any(res.culled & res.weak)
    assert np.array_equal(res.weak[valid], res.stress[valid] > 60.0)


def test_local_cuts_equal_whole_plane_cuts(model):
    name, (v, f, sk, w) = model
    a = osteon.analyze(v, f, sk, w, interval=2.0)
    b = osteon.analyze(v, f, sk, w, interval=2.0, local_cuts=False)
    assert np.array_equal(a.valid, b.valid), name
    assert np.allclose(a.section_modulus, b.section_modulus, rtol=1e-12, equal_nan=True), name
    assert np.allclose(a.stress, b.stress, rtol=1e-12, equal_nan=True), name


def test_moment_arms_are_exact_on_a_real_model(data_dir):
    v, f, sk, w = load("arm")
    res = osteon.analyze(v, f, sk, w, interval=8.0)
    # independent check: the load point is a vertex at the reported distance, and no vertex
    # downstream on the same bone is farther
    for i in range(res.num_sections):
        if res.moment_arm[i] == 0:
            continue
        d = np.linalg.norm(res.load_point[i] - res.section_center[i])
        assert d == pytest.approx(res.moment_arm[i], rel=1e-12)
        assert np.min(np.linalg.norm(v - res.load_point[i], axis=1)) < 1e-9
        b = res.section_bone[i]
        axis = sk.tails[b] - sk.heads[b]
        axis /= np.linalg.norm(axis)
        own = (res.vertex_bone == b) & ((v - sk.heads[b]) @ axis >= res.section_param[i])
        if own.any():
            assert np.linalg.norm(v[own] - res.section_center[i], axis=1).max() <= d + 1e-9
