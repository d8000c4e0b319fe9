"""osteon.make_skeleton: an unrigged capsule gets an Armature (osteon.auto_skeleton), vertex
groups and an Armature modifier; then Analyze gives a varied stress colour layer."""

import bpy
import numpy as np
import pytest
from conftest import empty_scene
from osteon_blender import bridge


def _capsule(length=4.0, radius=0.5, n=24, stations=16, cap=5):
    """A closed capsule along X (Blender units): (V,3) vertices, (F,4/3) faces."""
    rings = []
    for k in range(1, cap + 1):  # left cap
        a = np.pi / 2 * (1 - k / cap)
        rings.append((-radius * np.sin(a), radius * np.cos(a)))
    for k in range(1, stations):
        rings.append((length * k / stations, radius))
    for k in range(cap):
        a = np.pi / 2 * k / cap
        rings.append((length + radius * np.sin(a), radius * np.cos(a)))
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    verts = [(-radius, 0.0, 0.0)]
    for x, r in rings:
        verts += [(x, r * np.cos(a), r * np.sin(a)) for a in t]
    verts.append((length + radius, 0.0, 0.0))
    nr = len(rings)
    faces = [(0, 1 + (j + 1) % n, 1 + j) for j in range(n)]
    for i in range(nr - 1):
        a, b = 1 + i * n, 1 + (i + 1) * n
        faces += [(a + j, a + (j + 1) % n, b + (j + 1) % n, b + j) for j in range(n)]
    last, top = 1 + (nr - 1) * n, len(verts) - 1
    faces += [(last + j, last + (j + 1) % n, top) for j in range(n)]
    return verts, faces


@pytest.fixture
def capsule(addon):
    empty_scene()
    v, f = _capsule()
    me = bpy.data.meshes.new("capsule")
    me.from_pydata(v, [], f)
    me.update()
    obj = bpy.data.objects.new("capsule", me)
    bpy.context.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    s = bpy.context.scene.osteon
    s.size_mode = "LARGEST"
    s.print_size_mm = 40.0
    s.force_n = 80.0  # a thin 40 mm capsule under 80 N: stresses around the allowable, none culled
    yield obj
    for o in list(bpy.data.objects):
        bpy.data.objects.remove(o, do_unlink=True)


def test_make_skeleton_then_analyze_gives_a_varied_layer(capsule, engine):
    obj = capsule
    co = bridge.local_positions(obj.data)
    assert bridge.armature_of(obj) is None
    assert bpy.ops.osteon.make_skeleton() == {"FINISHED"}
    arm = bridge.armature_of(obj)
    assert arm is not None and arm.type == "ARMATURE"
    names = [b.name for b in arm.data.bones]
    assert len(names) >= 1
    assert {g.name for g in obj.vertex_groups} == set(names)
    # bones lie along the capsule's axis (X), inside it, and span most of its length
    heads = np.array([arm.matrix_world @ b.head_local for b in arm.data.bones])
    tails = np.array([arm.matrix_world @ b.tail_local for b in arm.data.bones])
    pts = np.concatenate([heads, tails])
    assert np.abs(pts[:, 1:]).max() < 0.5
    assert pts[:, 0].max() - pts[:, 0].min() > 3.5
    # the mesh is not changed; every vertex has weight
    assert np.array_equal(bridge.local_positions(obj.data), co)
    csr = bridge.vertex_weights_csr(obj, names)
    w = bridge.sparse_weights(csr, len(names)).toarray()
    assert np.allclose(w.sum(1), 1.0, atol=2e-3)
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    rgba = bridge.read_point_colors(obj.data)
    assert rgba.shape == (len(obj.data.vertices), 4)
    assert rgba[:, :3].std(axis=0).max() > 0.05, "stress layer is flat"
    # a second Make skeleton on the rigged mesh is refused with a message
    assert bridge.armature_of(obj) is not None
    with pytest.raises(RuntimeError, match="already has an Armature"):
        bpy.ops.osteon.make_skeleton()


def test_make_skeleton_blender_weights_option(capsule):
    obj = capsule
    assert bpy.ops.osteon.make_skeleton(blender_weights=True) == {"FINISHED"}
    arm = bridge.armature_of(obj)
    assert arm is not None and obj.parent == arm
    assert len(obj.vertex_groups) >= 1


def test_make_skeleton_is_undone_by_ctrl_z(capsule):
    """Ctrl+Z removes the armature, the groups and the modifier.  Background Blender starts
    with undo off: ``ed.undo_push`` initialises it, and the operator is called with undo on
    (as from the UI), so ``ed.undo`` is a real undo step here."""
    assert "UNDO" in bpy.types.OSTEON_OT_make_skeleton.bl_options
    name = capsule.name
    bpy.ops.ed.undo_push(message="before Make skeleton")
    assert bpy.ops.osteon.make_skeleton("EXEC_DEFAULT", True) == {"FINISHED"}
    assert any(o.type == "ARMATURE" for o in bpy.data.objects)
    assert bpy.ops.ed.undo() == {"FINISHED"}
    assert not any(o.type == "ARMATURE" for o in bpy.data.objects)
    obj = bpy.data.objects[name]  # undo reloads the datablocks
    assert bridge.armature_of(obj) is None
    assert not any(m.type == "ARMATURE" for m in obj.modifiers)
    assert len(obj.vertex_groups) == 0
