"""Clear errors (report -> RuntimeError when called from Python) and no change on failure."""

import bpy
import numpy as np
import pytest
from conftest import activate, empty_scene
from osteon_blender import bridge


def _snapshot():
    out = {}
    for o in bpy.context.scene.objects:
        if o.type == "MESH":
            out[o.name] = (bridge.local_positions(o.data).tobytes(),
                           sorted(a.name for a in o.data.attributes), len(o.vertex_groups))
        if o.type == "ARMATURE":
            out[o.name] = [(p.name, tuple(p.scale), tuple(p.location)) for p in o.pose.bones]
            out[o.name + ":inherit"] = [b.inherit_scale for b in o.data.bones]
    return out


OPS = ("analyze", "correct", "reset", "apply")


@pytest.mark.parametrize("op", OPS)
def test_no_active_object(addon, op):
    empty_scene()
    with pytest.raises(RuntimeError, match="No active object"):
        getattr(bpy.ops.osteon, op)()


@pytest.mark.parametrize("op", OPS)
def test_non_mesh_object(sample, op):
    cam = bpy.data.objects.new("Cam", bpy.data.cameras.new("Cam"))
    bpy.context.scene.collection.objects.link(cam)
    activate(cam)
    before = _snapshot()
    with pytest.raises(RuntimeError, match="'Cam' is a camera, not a mesh"):
        getattr(bpy.ops.osteon, op)()
    assert _snapshot() == before


@pytest.mark.parametrize("op", OPS)
def test_no_armature(addon, op):
    empty_scene()
    me = bpy.data.meshes.new("Box")
    me.from_pydata([(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)], [],
                   [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)])
    box = bpy.data.objects.new("Box", me)
    bpy.context.scene.collection.objects.link(box)
    activate(box)
    before = _snapshot()
    with pytest.raises(RuntimeError, match="no Armature modifier"):
        getattr(bpy.ops.osteon, op)()
    assert _snapshot() == before


@pytest.mark.parametrize("op", ["analyze", "correct"])
def test_no_vertex_groups(sample, op):
    obj, _arm = sample
    obj.vertex_groups.clear()
    before = _snapshot()
    with pytest.raises(RuntimeError, match="no vertex groups named after deform bones"):
        getattr(bpy.ops.osteon, op)()
    assert _snapshot() == before


def test_edit_mode_is_refused(sample):
    bpy.ops.object.mode_set(mode="EDIT")
    try:
        with pytest.raises(RuntimeError, match="Edit Mode"):
            bpy.ops.osteon.analyze()
    finally:
        bpy.ops.object.mode_set(mode="OBJECT")


def test_bad_settings_and_engine_errors_change_nothing(sample):
    obj, arm = sample
    assert bpy.ops.osteon.analyze() == {"FINISHED"}   # a previous result stays as it was
    colours = bridge.read_point_colors(obj.data).copy()
    before = _snapshot()
    s = bpy.context.scene.osteon
    s.held_bone = "no_such_bone"
    with pytest.raises(RuntimeError, match="Held bone 'no_such_bone'"):
        bpy.ops.osteon.correct()
    s.held_bone = ""
    # a zero-length deform bone: the engine refuses the skeleton, the add-on says so
    bpy.context.view_layer.objects.active = arm
    bpy.ops.object.mode_set(mode="EDIT")
    eb = arm.data.edit_bones.new("stub")
    eb.head = eb.tail = (0.0, 0.0, 0.5)
    bpy.ops.object.mode_set(mode="OBJECT")
    activate(obj)
    before = _snapshot()
    bpy.ops.object.mode_set(mode="OBJECT")
    # Blender <= 4.x drops a zero-length bone on leaving Edit Mode; 5.2 keeps it (~2e-6 long)
    if "stub" in arm.data.bones:
        with pytest.raises(RuntimeError, match="Bone 'stub' .*zero length"):
            bpy.ops.osteon.correct()
    assert _snapshot() == before
    assert np.array_equal(bridge.read_point_colors(obj.data), colours)


def test_posed_zero_length_bone_is_refused(sample):
    """A deform bone posed to zero length (scale 0 along its axis) has no axis: every Blender
    keeps it, the bridge refuses it by name and nothing changes."""
    obj, arm = sample
    arm.pose.bones["forearm.L"].scale = (1.0, 0.0, 1.0)
    bpy.context.view_layer.update()
    before = _snapshot()
    for op in ("analyze", "correct"):
        with pytest.raises(RuntimeError, match="Bone 'forearm.L' .*zero length"):
            getattr(bpy.ops.osteon, op)()
    assert _snapshot() == before
    assert obj.data.attributes.get(bridge.LAYER) is None


def test_apply_without_correction_is_refused(sample):
    before = _snapshot()
    with pytest.raises(RuntimeError, match="Nothing to apply"):
        bpy.ops.osteon.apply()
    assert _snapshot() == before
