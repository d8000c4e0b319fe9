"""osteon.analyze in Blender: posed world-space input in mm, the stress colour layer."""

import bpy
import numpy as np
import pytest
from conftest import activate, import_rignet
from osteon_blender import bridge, compat, core, printdir
from osteon_blender import service as common


def _layer(obj):
    attr = obj.data.attributes.get(bridge.LAYER)
    assert attr is not None, "no osteon_stress layer"
    assert attr.domain == "POINT" and attr.data_type == "FLOAT_COLOR"
    return bridge.read_point_colors(obj.data)


def _assert_non_flat(rgba, n):
    assert rgba.shape == (n, 4)
    assert np.all(np.isfinite(rgba))
    assert rgba[:, :3].std(axis=0).max() > 0.05, "stress layer is flat"


def test_analyze_sample_rig(sample, engine):
    obj, arm = sample
    co_before = bridge.local_positions(obj.data)
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    rgba = _layer(obj)
    _assert_non_flat(rgba, len(obj.data.vertices))
    assert obj.data.color_attributes.active_color.name == bridge.LAYER
    # the layer is exactly the engine's vertex stress through the colour map
    last = common.LAST[bpy.context.scene.name]
    a = last["analysis"]
    assert isinstance(a, engine.Analysis)
    # (PLA: layer ratio 0.55, so the stress is scaled by in-plane / layer-angle allowable)
    sk, k = last["inputs"].skeleton, last["inputs"].mm_per_unit
    shown = printdir.colour_stress(a, sk.heads * k, sk.tails * k)
    assert np.all(shown >= a.vertex_stress - 1e-12)  # never below the stress itself
    expect = core.stress_colors(shown, 30.0, a.vertex_culled)
    assert np.allclose(rgba, expect, atol=1e-6)
    # something is weak at the default load, the body is not
    s = bpy.context.scene.osteon
    names = [b.name for b in s.weak_bones]
    assert "tail" in names and "spine" not in names
    assert all(b.ratio > 1.0 for b in s.weak_bones)
    assert s.max_stress_mpa == pytest.approx(float(a.max_stress))
    assert s.allowable_mpa == pytest.approx(30.0)
    # the mesh itself is untouched and the pose too
    assert np.array_equal(bridge.local_positions(obj.data), co_before)
    assert all(tuple(p.scale) == (1.0, 1.0, 1.0) for p in arm.pose.bones)


def test_input_is_posed_world_space_mm(sample):
    obj, arm = sample
    scene = bpy.context.scene
    arm.location = (5.0, 0.0, 0.0)
    arm.pose.bones["tail"].rotation_mode = "XYZ"
    arm.pose.bones["tail"].rotation_euler = (0.0, 0.0, 1.2)
    bpy.context.view_layer.update()
    inp = common.gather(bpy.context)
    z = inp.vertices_mm[:, 2]
    assert z.max() - z.min() == pytest.approx(120.0, rel=1e-6)  # printed height
    world = bridge.evaluated_positions(obj, bpy.context.evaluated_depsgraph_get())
    assert np.allclose(inp.vertices_mm, world * inp.mm_per_unit)
    rest = bridge.local_positions(obj.data) + np.array([5.0, 0.0, 0.0])
    tail_only = bridge.vertex_weights_csr(obj, inp.skeleton.names)
    moved = np.linalg.norm(world - rest, axis=1) > 1e-4
    t = inp.skeleton.names.index("tail")
    rows = np.repeat(np.arange(len(rest)), np.diff(tail_only[2]))
    on_tail = np.zeros(len(rest), bool)
    on_tail[rows[tail_only[1] == t]] = True
    assert moved.any() and np.array_equal(moved, on_tail)
    # bones: posed, world space, mm
    ti = inp.skeleton.names.index("tail")
    pb = arm.pose.bones["tail"]
    assert np.allclose(inp.skeleton.tails[ti], np.array(arm.matrix_world @ pb.tail))
    scene.osteon.size_mode = "UNITS"
    scene.unit_settings.scale_length = 0.01  # 1 BU = 1 cm
    assert common.gather(bpy.context).mm_per_unit == pytest.approx(10.0)


def test_analyze_with_armature_active_and_held_bone(sample):
    obj, arm = sample
    activate(arm)
    bpy.context.scene.osteon.held_bone = "head"
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    assert bpy.context.scene.osteon.result_object == obj.name
    inp = common.LAST[bpy.context.scene.name]["inputs"]
    assert inp.root == inp.skeleton.names.index("head") and inp.params["root"] == inp.root
    _assert_non_flat(_layer(obj), len(obj.data.vertices))


def test_clicking_a_weak_bone_row_selects_the_bone(sample):
    _obj, arm = sample
    bpy.context.scene.osteon.force_n = 60.0
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    s = bpy.context.scene.osteon
    assert len(s.weak_bones) >= 2
    for i in (1, 0):
        s.weak_bones_index = i
        name = s.weak_bones[i].name
        assert arm.data.bones.active.name == name
        assert [b.name for b in arm.data.bones if compat.bone_selected(arm, b.name)] == [name]
    assert bpy.ops.osteon.select_bone(bone="forearm.L") == {"FINISHED"}
    assert arm.data.bones.active.name == "forearm.L"


@pytest.mark.parametrize("model", ["2982", "11814"])
def test_analyze_real_rignet_fbx(addon, model):
    obj, arm = import_rignet(model)
    activate(arm)  # as the FBX importer leaves it
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    rgba = _layer(obj)
    _assert_non_flat(rgba, len(obj.data.vertices))
    rep = common.LAST[bpy.context.scene.name]["report"]
    assert rep["sections"] > 50 and rep["max_stress_mpa"] > 0.0
    # FBX rigs come in cm with a 0.01 armature scale: world-space reading gives 120 mm
    inp = common.LAST[bpy.context.scene.name]["inputs"]
    assert np.ptp(inp.vertices_mm[:, 2]) == pytest.approx(120.0, rel=1e-6)
    assert np.all(np.isfinite(inp.skeleton.heads))


@pytest.mark.parametrize("model", ["sample", "2982", "11814"])
def test_weight_reading_methods_agree(addon, model):
    """The bulk (Geometry Nodes) weight read equals the per-vertex loop and leaves nothing."""
    from conftest import empty_scene
    from osteon_blender import sample as make_sample_rig

    if model == "sample":
        empty_scene()
        obj, arm = make_sample_rig.build()
    else:
        obj, arm = import_rignet(model)
    n_obj, n_ng = len(bpy.data.objects), len(bpy.data.node_groups)
    names = bridge.skeleton_arrays(arm).names
    fast = bridge.vertex_weights_csr(obj, names, method="nodes")
    slow = bridge.vertex_weights_csr(obj, names, method="loop")
    assert np.array_equal(fast[2], slow[2]) and np.array_equal(fast[1], slow[1])
    assert np.allclose(fast[0], slow[0], rtol=0, atol=1e-7)
    assert len(fast[2]) == len(obj.data.vertices) + 1 and fast[2][-1] > 0
    assert (len(bpy.data.objects), len(bpy.data.node_groups)) == (n_obj, n_ng)
