"""Correction: pose-bone scales across the bone axis reproduce the engine's skinning."""

import bpy
import numpy as np
import pytest
from osteon_blender import bridge
from osteon_blender import service as common


def _eval(obj):
    bpy.context.view_layer.update()
    return bridge.evaluated_positions(obj, bpy.context.evaluated_depsgraph_get())


def _pose_state(arm):
    return ([tuple(p.scale) for p in arm.pose.bones], [tuple(p.location) for p in arm.pose.bones],
            [b.inherit_scale for b in arm.data.bones],
            [np.array(p.matrix) for p in arm.pose.bones])


def _weight_on(obj, names, bones):
    _data, idx, indptr = bridge.vertex_weights_csr(obj, names)
    rows = np.repeat(np.arange(len(indptr) - 1), np.diff(indptr))
    mask = np.zeros(len(indptr) - 1, bool)
    mask[rows[np.isin(idx, [names.index(b) for b in bones])]] = True
    return mask


def test_correct_matches_engine_and_only_scales_across(sample, engine):
    obj, arm = sample
    rest_world = _eval(obj)
    assert bpy.ops.osteon.correct() == {"FINISHED"}
    last = common.LAST[bpy.context.scene.name]
    fix, inp = last["correction"], last["inputs"]
    assert isinstance(fix, engine.Correction) and fix.converged
    scaled = {n for n, s in zip(inp.skeleton.names, fix.bone_scale) if s != 1.0}
    assert "tail" in scaled
    for p in arm.pose.bones:
        sx, sy, sz = p.scale
        if p.name in scaled:
            s = float(fix.bone_scale[inp.skeleton.names.index(p.name)])
            assert sx == pytest.approx(s, rel=1e-6) and sz == pytest.approx(s, rel=1e-6)
            assert sy == 1.0  # the bone's length is kept
        else:
            assert (sx, sy, sz) == (1.0, 1.0, 1.0)
    # Blender's own armature deformation reproduces the engine's corrected mesh
    size = np.ptp(fix.vertices, axis=0).max()
    assert np.abs(inp.vertices_mm - fix.vertices).max() <= 1e-4 * size
    # no vertex without weight on a scaled bone moves
    after_world = _eval(obj)
    free = ~_weight_on(obj, inp.skeleton.names, scaled)
    # enough unweighted vertices for the check to mean something (since the sharper Kt of
    # docs/notch.md round 4 the loop also scales the head and both thighs: 45 % stay free)
    assert free.sum() > 0.3 * len(free)
    assert np.abs(after_world[free] - rest_world[free]).max() < 1e-6
    assert np.abs(after_world[~free] - rest_world[~free]).max() > 1e-3
    # the result shown is Blender's corrected mesh: nothing weak left; the list shows
    # the bones that were weak or were scaled, with their scale (a bone weak before may be
    # fixed by scaling its neighbour: the neck by the head)
    before = fix.before
    weak_before = {inp.skeleton.names[b] for b in np.unique(before.section_bone[before.weak])}
    shown = scaled | weak_before
    rows = bpy.context.scene.osteon.weak_bones
    assert {r.name for r in rows} == shown and not any(r.weak for r in rows)
    assert all(r.ratio <= 1.0 and (r.scale > 1.0) == (r.name in scaled) for r in rows)
    assert last["report"]["converged"] is True
    assert {b["bone"] for b in last["report"]["weak_bones"]} == shown


def _flatten_tail(obj, factor: float = 0.4):
    """Squash the figurine's tail across world z about its axis (blended by its weight): a
    flat tail, wide in x and thin in z."""
    from osteon_blender import sample as make_sample_rig

    a = np.array(make_sample_rig.JOINTS["tail_base"][0])
    b = np.array(make_sample_rig.JOINTS["tail_tip"][0])
    gi = obj.vertex_groups["tail"].index
    co = bridge.local_positions(obj.data)
    w = np.array([next((g.weight for g in v.groups if g.group == gi), 0.0)
                  for v in obj.data.vertices])
    t = np.clip((co - a) @ (b - a) / ((b - a) @ (b - a)), 0.0, 1.0)
    axis_z = a[2] + t * (b[2] - a[2])
    co[:, 2] = axis_z + (co[:, 2] - axis_z) * (1.0 - (1.0 - factor) * w)
    bridge.set_local_positions(obj.data, co)


@pytest.mark.parametrize("scaling", ["THIN", "UNIFORM"])
def test_flat_part_pose_scales_reproduce_the_engine(sample, engine, scaling):
    """A flat tail: THIN thickens it on one pose axis only, UNIFORM on both; either way
    Blender's deformation of the pose scales is the engine's corrected mesh."""
    obj, arm = sample
    _flatten_tail(obj)
    bpy.context.scene.osteon.scaling = scaling
    assert bpy.ops.osteon.correct() == {"FINISHED"}
    last = common.LAST[bpy.context.scene.name]
    fix, inp = last["correction"], last["inputs"]
    names = inp.skeleton.names
    tail = names.index("tail")
    # UNIFORM, scaling the flat tail on both axes, may reach max_scale first (its base is a
    # corner, docs/notch.md: the peak there falls slowly with a uniform scale). Either may stop
    # at the tail's root corner, which sits under blended joint weights (docs/notch.md
    # "Correction": THIN stops 5 % over since round 4's Kt); the stop must then say so.
    after = fix.after
    stuck_at_corner = (not fix.converged and "a corner at a joint" in fix.reason
                       and "a larger fillet there lowers the peak" in fix.reason
                       and bool((after.stress_concentration[after.weak] > 1.0).all()))
    assert fix.converged or stuck_at_corner or (scaling == "UNIFORM"
                                                and fix.bone_scale[tail] == pytest.approx(3.0))
    sx, sy, sz = arm.pose.bones["tail"].scale
    assert sy == 1.0
    assert sx == pytest.approx(fix.bone_scale_x[tail], rel=1e-6)
    assert sz == pytest.approx(fix.bone_scale_z[tail], rel=1e-6)
    if scaling == "THIN":
        # flat: thickened across its thickness (one pose axis) until it is no longer flat
        assert {r[3] for r in fix.rounds if r[0] == tail} & {1, 2}
        assert max(sx, sz) > 1.2 * min(sx, sz)
    else:
        assert sx == pytest.approx(sz) and sx > 1.0
    size = np.ptp(fix.vertices, axis=0).max()
    assert np.abs(inp.vertices_mm - fix.vertices).max() <= 1e-4 * size
    report = last["report"]
    assert report["settings"]["scaling"] == scaling
    assert report["correction"]["bone_scale_xz"]["tail"] == pytest.approx([sx, sz], rel=1e-6)
    # Apply bakes the same shape into the mesh
    corrected = _eval(obj)
    assert bpy.ops.osteon.apply("EXEC_DEFAULT") == {"FINISHED"}
    assert np.abs(_eval(obj) - corrected).max() < 1e-4 * np.ptp(corrected, axis=0).max()


@pytest.mark.parametrize("bone", ["spine", "upper_arm.L", "thigh.R"])
def test_children_keep_shape_and_place(sample, engine, bone):
    """Scale a bone with children: Blender == osteon.skin, children's matrices unchanged."""
    obj, arm = sample
    inp = common.gather(bpy.context)
    before = {p.name: np.array(p.matrix) for p in arm.pose.bones}
    names = inp.skeleton.names
    scale = np.ones(len(names))
    scale[names.index(bone)] = 1.7
    bridge.apply_bone_scales(bpy.context, arm, {bone: 1.7})
    for p in arm.pose.bones:
        if p.name != bone:
            assert np.abs(np.array(p.matrix) - before[p.name]).max() < 1e-5, p.name
    sk = common.engine_skeleton(engine, inp)
    expect = engine.skin(inp.vertices_mm, sk, inp.weights, scale)
    got = _eval(obj) * inp.mm_per_unit
    assert np.abs(got - expect).max() <= 1e-4 * np.ptp(expect, axis=0).max()
    assert np.abs(got - inp.vertices_mm).max() > 0.5  # it did thicken (mm)


def test_reset_restores_pose_and_removes_layer(sample):
    obj, arm = sample
    state0 = _pose_state(arm)
    world0 = _eval(obj)
    bpy.context.scene.osteon.force_n = 60.0  # several bones, some with children
    assert bpy.ops.osteon.correct() == {"FINISHED"}
    assert bridge.has_saved_pose(arm)
    assert any(b.inherit_scale == "NONE" for b in arm.data.bones)
    assert bpy.ops.osteon.reset() == {"FINISHED"}
    s1 = _pose_state(arm)
    assert s1[:3] == state0[:3]
    assert all(np.allclose(a, b, atol=1e-6) for a, b in zip(s1[3], state0[3]))
    assert obj.data.attributes.get(bridge.LAYER) is None
    assert not bridge.has_saved_pose(arm)
    assert np.abs(_eval(obj) - world0).max() < 1e-6
    assert len(bpy.context.scene.osteon.weak_bones) == 0


def test_correct_twice_is_idempotent_and_keeps_user_pose(sample):
    _obj, arm = sample
    arm.pose.bones["tail"].scale = (1.1, 0.9, 1.1)  # the user's own pose scale
    arm.pose.bones["forearm.L"].rotation_mode = "XYZ"
    arm.pose.bones["forearm.L"].rotation_euler = (0.0, 0.0, 0.5)
    assert bpy.ops.osteon.correct() == {"FINISHED"}
    first = [tuple(p.scale) for p in arm.pose.bones]
    assert bpy.ops.osteon.correct() == {"FINISHED"}
    assert np.allclose([tuple(p.scale) for p in arm.pose.bones], first, rtol=1e-6)
    assert bpy.ops.osteon.reset() == {"FINISHED"}
    assert tuple(arm.pose.bones["tail"].scale) == pytest.approx((1.1, 0.9, 1.1))
    assert tuple(arm.pose.bones["forearm.L"].rotation_euler) == pytest.approx((0.0, 0.0, 0.5))


def test_undo_restores(sample):
    """Blender's undo stack, driven in background mode (ed.undo_push / ed.undo)."""
    obj, arm = sample
    obj_name, arm_name = obj.name, arm.name
    bpy.ops.ed.undo_push(message="before osteon")
    assert bpy.ops.osteon.correct() == {"FINISHED"}
    bpy.ops.ed.undo_push(message="after osteon")
    arm = bpy.data.objects[arm_name]
    assert any(tuple(p.scale) != (1.0, 1.0, 1.0) for p in arm.pose.bones)
    assert bridge.has_saved_pose(arm)
    bpy.ops.ed.undo()
    arm = bpy.data.objects[arm_name]
    obj = bpy.data.objects[obj_name]
    assert all(tuple(p.scale) == (1.0, 1.0, 1.0) for p in arm.pose.bones)
    assert all(b.inherit_scale == "FULL" for b in arm.data.bones)
    assert obj.data.attributes.get(bridge.LAYER) is None
    assert not bridge.has_saved_pose(arm)


def test_apply_bakes_correction_into_mesh(sample):
    obj, arm = sample
    co0 = bridge.local_positions(obj.data)
    assert bpy.ops.osteon.correct() == {"FINISHED"}
    corrected = _eval(obj)
    assert bpy.ops.osteon.apply("EXEC_DEFAULT") == {"FINISHED"}
    assert not bridge.has_saved_pose(arm)
    assert all(tuple(p.scale) == (1.0, 1.0, 1.0) for p in arm.pose.bones)
    co1 = bridge.local_positions(obj.data)
    assert np.abs(co1 - co0).max() > 1e-3       # the rest mesh changed ...
    size = np.ptp(corrected, axis=0).max()
    assert np.abs(_eval(obj) - corrected).max() < 1e-4 * size  # ... into the corrected shape
    assert not any(r.weak for r in bpy.context.scene.osteon.weak_bones)


@pytest.mark.parametrize("scaling", ["THIN", "UNIFORM"])
@pytest.mark.parametrize("model", ["2982", "11814"])
def test_correct_real_rignet_fbx_matches_engine(addon, model, scaling):
    """FBX rigs: armature object scaled 0.01 and rotated; heavier children chains."""
    from conftest import import_rignet

    obj, arm = import_rignet(model)
    bpy.context.scene.osteon.force_n = 40.0  # make sure something needs thickening
    bpy.context.scene.osteon.scaling = scaling
    before = _eval(obj)
    assert bpy.ops.osteon.correct() == {"FINISHED"}
    last = common.LAST[bpy.context.scene.name]
    fix, inp = last["correction"], last["inputs"]
    scaled = {n for n, s in zip(inp.skeleton.names, fix.bone_scale) if s != 1.0}
    # RigNet FBX files are joint rigs: the engine gets the joints' segments (issue 13), on which
    # 11814 has nothing weak at 40 N (its weak bones came from Blender's upright tails)
    joint_rig = inp.skeleton.segment_changed is not None and inp.skeleton.segment_changed.any()
    if not scaled:
        assert joint_rig and fix.converged and last["report"]["verdict"] != "weak"
        return
    size = np.ptp(fix.vertices, axis=0).max()
    err = np.abs(inp.vertices_mm - fix.vertices).max() / size
    # a joint-rig bone's segment need not be one of its local axes: the engine then scales it
    # across the local axis nearest the segment (bone_long_axes), as its pose scale does
    assert err <= 1e-4
    free = ~_weight_on(obj, inp.skeleton.names, scaled)
    assert np.abs(_eval(obj)[free] - before[free]).max() < 1e-6 * np.ptp(before, axis=0).max()
    for p in arm.pose.bones:
        if p.name in scaled:
            # the bone's cross-section scales sit on two of its local axes, the third is 1
            b = inp.skeleton.names.index(p.name)
            got = sorted(p.scale)
            want = sorted([fix.bone_scale_x[b], fix.bone_scale_z[b], 1.0])
            assert got == pytest.approx(want, rel=1e-6)
    assert bpy.ops.osteon.reset() == {"FINISHED"}
    assert np.abs(_eval(obj) - before).max() < 1e-6 * np.ptp(before, axis=0).max()


def test_correct_on_posed_rig(sample):
    """Posed rig: Blender deforms the rest mesh, the engine the posed mesh. They agree
    exactly where a vertex follows one bone (or bones with one pose transform), and
    differ by far less than 1 % of the model size where weights blend bent bones (for the
    scales a 40 N load asks: since round 6's acute-corner Kt, docs/notch.md, 60 N drives
    upper_arm.L to the 3.0 cap, where the blended vertices differ by 1.2 %)."""
    obj, arm = sample
    for name, angle in (("forearm.L", 0.8), ("tail", 0.6), ("upper_arm.R", -0.5)):
        pb = arm.pose.bones[name]
        pb.rotation_mode = "XYZ"
        pb.rotation_euler = (0.3, 0.0, angle)
    bpy.context.scene.osteon.force_n = 40.0
    assert bpy.ops.osteon.correct() == {"FINISHED"}
    last = common.LAST[bpy.context.scene.name]
    fix, inp = last["correction"], last["inputs"]
    names = inp.skeleton.names
    scaled = {n for n, s in zip(names, fix.bone_scale) if s != 1.0}
    assert {"tail", "upper_arm.L"} <= scaled
    d = np.linalg.norm(inp.vertices_mm - fix.vertices, axis=1)
    size = np.ptp(fix.vertices, axis=0).max()
    _data, _idx, indptr = bridge.vertex_weights_csr(obj, names)
    single = np.diff(indptr) == 1
    assert d[single].max() <= 1e-4 * size
    assert d.max() <= 1e-2 * size
    assert np.median(d) <= 1e-5 * size
    # the pose itself (rotations) is untouched by Correct and restored exactly by Reset
    assert tuple(arm.pose.bones["tail"].rotation_euler) == pytest.approx((0.3, 0.0, 0.6))
    assert bpy.ops.osteon.reset() == {"FINISHED"}
    assert all(tuple(p.scale) == (1.0, 1.0, 1.0) for p in arm.pose.bones)


def test_correct_warns_when_blender_cannot_match(sample):
    obj, _arm = sample
    obj.modifiers["Armature"].use_deform_preserve_volume = True
    assert bpy.ops.osteon.correct() == {"FINISHED"}
    warnings = common.LAST[bpy.context.scene.name]["report"]["warnings"]
    assert any("Preserve Volume" in w for w in warnings)
