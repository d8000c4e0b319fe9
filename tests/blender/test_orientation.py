"""Find best orientation + Apply orientation (issue 18) on the sample rig, PLA (layer ratio
0.55): Apply turns the object so the found direction is +Z, the reported worst stress ratio
drops to best_orientation's, and putting the matrices back (ops/orientation.revert, the
stored state: bpy.ops.ed.undo needs a window and does nothing headless) restores the ratio."""

import bpy
import numpy as np
import pytest
from osteon_blender import state
from osteon_blender.ops import orientation as orient


def _world(o):
    return np.array([list(r) for r in o.matrix_world], float)


def test_find_and_apply_orientation_lowers_the_worst_ratio(sample, engine):
    obj, arm = sample
    s = bpy.context.scene.osteon
    s.material = "PLA"
    assert s.layer_strength_ratio == pytest.approx(0.55)  # the preset's, as the CLI takes it
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    st = state.of(bpy.context.scene)
    before = st.last["report"]["stress_ratio"]
    assert st.last["report"]["layer_strength_ratio"] == pytest.approx(0.55)
    assert bpy.ops.osteon.find_orientation() == {"FINISHED"}
    o = st.orientation
    res = o["result"]
    assert o["before"] == pytest.approx(before, rel=1e-9)
    # an independent check of the search: the worst ratio at the found direction
    assert engine.orientation.worst_ratios(st.last["analysis"], [res.direction])[0][0] == \
        pytest.approx(res.worst_ratio, rel=1e-9)
    assert res.worst_ratio < before  # the sample rig is better printed otherwise
    assert bpy.data.objects.get(orient.PREVIEW) is not None
    m_obj, m_arm = _world(obj), _world(arm)
    d = np.asarray(res.direction, float)
    assert bpy.ops.osteon.apply_orientation() == {"FINISHED"}
    assert not np.allclose(_world(obj), m_obj) and not np.allclose(_world(arm), m_arm)
    turn = _world(arm)[:3, :3] @ np.linalg.inv(m_arm[:3, :3])
    assert np.abs(turn @ d - [0, 0, 1]).max() < 1e-6
    turn_obj = _world(obj)[:3, :3] @ np.linalg.inv(m_obj[:3, :3])
    assert np.abs(turn_obj - turn).max() < 1e-6  # mesh and armature turned together
    after = st.last["report"]["stress_ratio"]
    assert list(st.last["report"]["build_direction"]) == [0.0, 0.0, 1.0]
    assert after <= before
    # the turned model is analysed anew: the beam stresses are the same to 1e-4; the corner
    # finder's sectors turn with the model now (docs/notch.md), but the turned mesh is stored by
    # Blender in float32, and a corner's sharpest sector can change with such rounding (before
    # the sectors turned, the sample read 1.97 against the search's 1.81; not re-measured)
    assert after == pytest.approx(res.worst_ratio, rel=0.1)
    assert bpy.data.objects.get(orient.PREVIEW) is None
    # undo: the stored matrices back, re-analysis gives the first ratio
    orient.revert(bpy.context)
    assert np.allclose(_world(obj), m_obj, atol=1e-9) and np.allclose(_world(arm), m_arm, atol=1e-9)
    assert st.last["report"]["stress_ratio"] == pytest.approx(before, rel=1e-6)


def test_chosen_axis_and_weak_list_limits(sample):
    _obj, _arm = sample
    s = bpy.context.scene.osteon
    s.material = "PLA"
    s.print_direction = "AXIS"
    s.print_axis = "+X"
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    rep = state.of(bpy.context.scene).last["report"]
    assert list(rep["build_direction"]) == [1.0, 0.0, 0.0]
    assert {w.limit for w in s.weak_bones} <= {"across layers", "along layers"}
    assert all(w.limit for w in s.weak_bones)


def test_best_found_needs_a_search(sample):
    s = bpy.context.scene.osteon
    s.print_direction = "BEST"
    state.of(bpy.context.scene).orientation = None
    try:
        with pytest.raises(RuntimeError, match="Find best orientation"):
            bpy.ops.osteon.analyze()
    finally:
        s.print_direction = "Z"
