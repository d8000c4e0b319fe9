"""Issue 13 in Blender: rigs made of joints (FBX/glTF imports) and no false all-clear on an
open mesh."""

import os

import bpy
import numpy as np
import pytest
from conftest import DATA, activate, import_rignet, one_bone_rig
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
    return one_bone_rig("open_cube", v, faces, "bone", (0, 0, -1), (0, 0, 1))


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


def _cli_dog(engine, height_mm, force, interval=2.0):
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
    m.names = list(names)
    return m, engine.analyze(m.vertices, m.faces, m.skeleton, m.weights, force=force,
                             allowable_stress=30.0, interval=interval)


def _analyze_dog(interval_mm):
    obj, arm = import_rignet("2982")
    activate(obj)
    s = bpy.context.scene.osteon
    s.size_mode, s.print_size_mm, s.force_n = "HEIGHT", 120.0, 20.0
    s.strength_mpa, s.safety_factor, s.interval_mm = 60.0, 2.0, interval_mm
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    return obj, arm, common.LAST[bpy.context.scene.name]


def test_fbx_dog_joint_segments_match_the_cli(addon, engine):
    """The FBX's rig is not the _rig.txt's: its joints sit up to 0.09 of the size away from
    the rig file's (the legs have four joints, not three) and its skin is its own.  The two
    agree where the stress is: the maximum is at the root of the tail, a narrow neck where the
    stress falls from 34 to 14 MPa within 2 mm; the FBX's tail joint sits 1.07 mm behind the
    rig file's, so sections every 2 mm land at different places on that peak (2 mm: FBX
    33.98, rig file 25.20 MPa, its max then on a leg).  At 0.5 mm both resolve the peak (39.24
    and 38.63 MPa, unchanged at 0.25 mm), so the comparison is made there.  It compares the beam
    (nominal) stress: the tail's root is also a step, and whether a section there carries a
    corner's Kt depends on where the sections fall on it (the step test compares neighbouring
    sections; docs/notch.md "Steps"): with the corner measured on meridian profiles (issue 33,
    round 5) the FBX's section at 5.5 mm reads Kt 1.45 at a 1.7 mm fillet, the rig file's
    sections 1.07 mm away none (before round 5 neither did)."""
    _obj, _arm, last = _analyze_dog(0.5)
    sk = last["inputs"].skeleton
    assert sk.segment_changed is not None and sk.segment_changed.sum() >= 10  # a joint rig
    an = last["analysis"]
    blender_max = float(np.nanmax(an.nominal_stress))
    m, a = _cli_dog(engine, 120.0, 20.0, interval=0.5)
    cli_max = float(np.nanmax(a.nominal_stress))
    print(f"[issue13] dog FBX max beam stress {blender_max:.2f} MPa, CLI {cli_max:.2f} MPa "
          "(0.5 mm)")
    assert blender_max == pytest.approx(cli_max, rel=0.10)
    # the same place: the tail's root (the rig file's joint_13 is the FBX's joint_9)
    # (by beam stress: the panel's weakest section is by stress ratio, which the print
    # direction's layer strength changes)
    worst = sk.names[an.section_bone[int(np.nanargmax(an.nominal_stress))]]
    assert worst == "joint_9" and \
        m.names[a.section_bone[int(np.nanargmax(a.nominal_stress))]] == "joint_13"


def test_live_mode_reads_the_joint_segments(addon, engine):
    """Live mode gives the engine the same skeleton as Analyze: the joint segments."""
    from osteon_blender import live

    _obj, _arm, last = _analyze_dog(2.0)
    sk = last["inputs"].skeleton
    assert sk.segment_changed.sum() >= 10
    try:
        r = live.start(bpy.context)
        assert r.status == "live", r.status
        res = live.session().last_result
        got, want = res.analysis, last["analysis"]
        # sections where the joint segments put them (Blender's tails would put them elsewhere)
        assert len(got.stress) == len(want.stress)
        size = np.ptp(last["inputs"].vertices_mm, axis=0).max()
        # (live reads float32 world positions, Analyze float64: 1e-7-level differences)
        assert np.abs(got.section_point - want.section_point).max() <= 1e-6 * size
        np.testing.assert_allclose(got.stress, want.stress, rtol=1e-4, atol=1e-9)
        assert got.max_stress == pytest.approx(want.max_stress, rel=1e-4)
    finally:
        live.stop()


def test_fbx_dog_correct_fixes_all_but_a_joint_corner_and_leaves_stay_modest(addon, engine):
    obj, arm = import_rignet("2982")
    activate(obj)
    s = bpy.context.scene.osteon
    s.size_mode, s.print_size_mm, s.force_n = "HEIGHT", 120.0, 40.0
    s.strength_mpa, s.safety_factor, s.interval_mm = 60.0, 2.0, 2.0
    assert bpy.ops.osteon.correct() == {"FINISHED"}
    last = common.LAST[bpy.context.scene.name]
    fix, inp = last["correction"], last["inputs"]
    print(f"[issue13] dog correct: converged {fix.converged} ({fix.reason})")
    if not fix.converged:
        # Since round 6's acute-corner Kt (docs/notch.md) a corner at joint_9's root (Kt 2.1 at a
        # 0.78 mm fillet) stops the loop with its documented reason: scaling the bone does not
        # thicken a corner at a joint, a larger fillet lowers the peak; every other section is
        # within the allowable.
        assert "does not thicken it" in fix.reason and "a corner at a joint" in fix.reason
        assert int(np.count_nonzero(fix.after.weak)) == 1
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
    assert err <= 1e-4
    # and some joint-rig bone was scaled across a local axis that is not its Blender Y axis
    # (the case the engine's bone_long_axes exists for), so the check above means something
    sk = inp.skeleton
    scaled = np.flatnonzero(np.asarray(fix.bone_scale) != 1.0)
    assert scaled.size and sk.long_axes is not None
    off = [float(np.degrees(np.arccos(np.clip(abs(sk.long_axes[b] @ (sk.tails[b] - sk.heads[b]))
                                              / np.linalg.norm(sk.tails[b] - sk.heads[b]), 0, 1))))
           for b in scaled]
    print(f"[issue13] scaled bones' segment vs scaled-across axis: {np.round(off, 1)} degrees")


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
    # the importer leaves the Fox posed at frame 1 of its first animation ("Survey"); the CLI
    # reads the bind pose: compare the rest pose (posed, Blender gives 18.64 MPa)
    bridge.armature_of(meshes[0]).data.pose_position = "REST"
    bpy.context.view_layer.update()
    s = bpy.context.scene.osteon
    s.size_mode, s.print_size_mm, s.force_n = "HEIGHT", 120.0, 20.0
    s.strength_mpa, s.safety_factor, s.interval_mm = 60.0, 2.0, 2.0
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    last = common.LAST[bpy.context.scene.name]
    rep = last["report"]
    blender_max = rep["max_stress_mpa"]
    assert last["inputs"].skeleton.segment_changed.sum() >= 15  # a joint rig
    print(f"[issue13] Fox glTF in Blender: max {blender_max:.2f} MPa, doubt {rep['doubt']}")
    # the maximum rests on a clean section (it was 446.6 MPa on an `outside` one before
    # issue 12's `unreliable` rule)
    assert rep["max_stress_doubt"] == []
    # the CLI side: the wheel's glTF reader needs pygltflib (scripts/blender_setup.sh installs
    # it into the bpy venvs, where Blender's glTF importer works)
    import pygltflib  # noqa: F401

    m = load_model(os.path.join(DATA, "glTF-Sample-Models", "Fox.glb"), height_mm=120.0,
                   axis="y")
    a = engine.analyze(m.vertices, m.faces, m.skeleton, m.weights, force=20.0,
                       allowable_stress=30.0, interval=2.0)
    print(f"[issue13] Fox glTF max {blender_max:.2f} MPa, CLI {a.max_stress:.2f} MPa")

    def beam_max(an):  # the largest beam stress of the sections that count
        ok = an.valid & ~an.too_thin & ~an.unreliable
        return float(np.nanmax(an.nominal_stress[ok]))

    # the beam stresses agree; a corner's Kt is measured on each mesh as it lies (Blender's
    # z-up float32 import against the CLI's y-up read in double): the finder turns with the
    # model (docs/notch.md), rounding can still move a sharpest sector: compare the beam stress
    assert beam_max(last["analysis"]) == pytest.approx(beam_max(a), rel=0.10)


def test_bridge_gives_the_readers_segments(addon, engine):
    """The RigNet dog rebuilt in Blender as a joint rig (one bone per joint, tails a stub up +Z,
    as Blender's FBX/glTF importers make them; the rig file's weights as vertex groups): the
    bridge (service.gather) gives the engine, for every bone the RigNet reader names after a
    joint, the reader's segment to 1e-6 of the model size."""
    import scipy.sparse as sp
    from conftest import empty_scene
    from osteon.io.rignet import read_rignet_rig, rignet_skeleton

    base = os.path.join(DATA, "RigNet", "2982_ori")
    raw = _raw_dog_vertices()
    m, _ = _cli_dog(engine, 120.0, 20.0)  # the dog in mm (120 mm along y)
    rig = read_rignet_rig(base + "_rig.txt")
    kk = np.ptp(m.vertices[:, 1]) / np.ptp(raw[:, 1])  # mm per OBJ unit
    v = m.vertices
    empty_scene()
    me = bpy.data.meshes.new("dog")
    me.from_pydata(v.tolist(), [], m.faces.tolist())
    me.update()
    obj = bpy.data.objects.new("dog", me)
    bpy.context.scene.collection.objects.link(obj)
    joints_mm = rig["positions"] * kk
    size = float(np.ptp(v, axis=0).max())
    stub = joints_mm + [0.0, 0.0, 0.05 * size]
    arm = bridge.build_armature(bpy.context, "dog_rig", joints_mm, stub, rig["parent"],
                                rig["names"])
    w = sp.csr_matrix((rig["skin_values"], (rig["skin_rows"], rig["skin_joints"])),
                      shape=(len(v), len(rig["names"])))
    bridge.write_bone_weights(obj, rig["names"], w)
    bridge.bind_armature(bpy.context, obj, arm)
    activate(obj)
    inp = common.gather(bpy.context)
    sk = inp.skeleton  # Blender units = the mm the mesh was built in
    assert sk.segment_changed.sum() >= 15
    rh, rt, _, rnames, _ = rignet_skeleton(rig, raw)
    idx = {n: i for i, n in enumerate(sk.names)}
    checked = 0
    for h, t, n in zip(rh * kk, rt * kk, rnames):
        if n not in idx:
            continue  # an edge of a branching joint ("a->b")
        i = idx[n]
        assert np.abs(sk.heads[i] - h).max() <= 1e-6 * size, n
        assert np.abs(sk.tails[i] - t).max() <= 1e-6 * size, n
        checked += 1
    assert checked == sum("->" not in x for x in rnames) and checked >= 15


def _raw_dog_vertices():
    v = []
    with open(os.path.join(DATA, "RigNet", "2982_ori.obj")) as fh:
        for line in fh:
            t = line.split()
            if t and t[0] == "v":
                v.append([float(x) for x in t[1:4]])
    return np.asarray(v)
