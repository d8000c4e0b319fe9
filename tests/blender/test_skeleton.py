"""osteon.make_skeleton: an unrigged capsule gets an Armature (osteon.auto_skeleton), vertex
groups and an Armature modifier; then Analyze gives a varied stress colour layer."""

import json
import os
import re
import shutil
import subprocess

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


def test_make_skeleton_writes_byte_weights_that_sum_to_one(capsule, engine):
    """Make skeleton writes the engine's weights in steps of 1/256 (glTF's byte weights: a third
    of the bpy calls of 1/1024, issue 35): every vertex's weights are multiples of 1/256, sum to
    exactly 1 and are within 1/256 of ``osteon.auto_skeleton``'s on the same mesh in mm."""
    obj = capsule
    co = bridge.world_rest_positions(obj)
    k = 40.0 / float(np.ptp(co, axis=0).max())  # LARGEST side printed at 40 mm
    _sk, want = engine.auto_skeleton(co * k, bridge.triangles(obj.data))
    assert bpy.ops.osteon.make_skeleton() == {"FINISHED"}
    names = [b.name for b in bridge.armature_of(obj).data.bones]
    got = bridge.sparse_weights(bridge.vertex_weights_csr(obj, names), len(names)).toarray()
    assert np.allclose(got * 256, np.round(got * 256), atol=1e-4)
    assert np.allclose(got.sum(1), 1.0, atol=1e-6)
    assert np.abs(got - want.toarray()).max() <= 1.0 / 256 + 1e-6
    from osteon_blender.service import WEIGHT_LEVELS

    assert WEIGHT_LEVELS == 256


def test_make_skeleton_without_pygel3d_says_what_to_do_in_blender(capsule, monkeypatch,
                                                                  tmp_path):
    """A zip for a platform PyPI has no pygel3d wheel for: the message tells a zip user what to
    do inside Blender (no repository script), and nothing is changed."""
    import sys

    from osteon_blender import core

    monkeypatch.setitem(sys.modules, "pygel3d", None)        # import pygel3d -> ImportError
    monkeypatch.setattr(core, "_VENDOR", str(tmp_path / "no_vendor"))
    with pytest.raises(RuntimeError) as err:
        bpy.ops.osteon.make_skeleton()
    msg = str(err.value)
    assert "pygel3d" in msg and "Python Console" in msg and "pip" in msg
    assert "blender_setup" not in msg and "scripts/" not in msg
    assert bridge.armature_of(capsule) is None and not capsule.vertex_groups


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


def test_make_skeleton_reports_the_loose_pieces_it_bound(capsule, capfd):
    """A capsule and a cube standing apart from it (issue 35): Make skeleton rigs the mesh and
    says, as a WARNING, that the cube touches nothing (its 8 vertices, the bone they are bound
    to) -- the wheel's LoosePiecesWarning, which the Python API emits, is not lost in Blender."""
    from conftest import run_op

    me = capsule.data
    n0 = len(me.vertices)
    co = np.vstack([bridge.local_positions(me),
                    [(x, y, z) for x in (6.0, 6.5) for y in (-0.25, 0.25) for z in (-0.25, 0.25)]])
    faces = [list(p.vertices) for p in me.polygons]
    cube = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    faces += [[n0 + i for i in q] for q in cube]
    me.clear_geometry()
    me.from_pydata(co.tolist(), [], faces)
    me.update()
    res, out = run_op(bpy.ops.osteon.make_skeleton, capfd)
    assert res == {"FINISHED"}
    arm = bridge.armature_of(capsule)
    names = [b.name for b in arm.data.bones]
    w = bridge.sparse_weights(bridge.vertex_weights_csr(capsule, names), len(names)).toarray()
    bound = names[int(w[n0:].argmax(1)[0])]
    assert np.all(w[n0:].max(1) == 1.0) and len(set(w[n0:].argmax(1))) == 1
    warning = [line for line in out.splitlines() if line.startswith("Warning")]
    assert len(warning) == 1, out
    assert f"Mesh '{capsule.name}': 1 loose piece" in warning[0]
    assert f"8 vertices at {bound}" in warning[0] and "Select Loose Pieces" in warning[0]
    assert re.search(r"Info: osteon: .*\d+ bones", out), out  # ... and the usual message


def _capsule_tip_distance_mm(obj, arm, mm_per_unit):
    """Farthest distance (mm) along the capsule's axis (X) from the held point (bone 0's head)
    to the mesh: the lever arm of the load at the root section."""
    hold = (arm.matrix_world @ arm.data.bones[0].head_local).x
    x = bridge.local_positions(obj.data)[:, 0]  # the capsule's object transform is identity
    return float(np.abs(x - hold).max()) * mm_per_unit


def test_batch_auto_skeleton_rigs_and_analyses_in_process(capsule, engine, tmp_path):
    """``batch.py --auto-skeleton`` (in this Blender): Make skeleton, then Analyze; the report's
    maximum stress is the cantilever's F·d/W at the hold (W = πr³/4 of the 4 mm radius, d the
    hold's distance to the far tip), within the polygon and section-spacing error."""
    from osteon_blender import batch

    rep = tmp_path / "r.json"
    assert batch.run(["--auto-skeleton", "--report", str(rep), "--print-size", "40",
                      "--force", "80", "--interval", "1"]) == 0
    arm = bridge.armature_of(capsule)
    assert arm is not None and len(arm.data.bones) >= 1
    data = json.loads(rep.read_text())
    assert data["sections"] > 10
    k = 40.0 / 5.0  # the capsule is 5 units long (-0.5 .. 4.5), printed 40 mm: 8 mm per unit
    d = _capsule_tip_distance_mm(capsule, arm, k)
    w = np.pi * (0.5 * k) ** 3 / 4
    assert data["max_stress_mpa"] == pytest.approx(80.0 * d / w, rel=0.15)
    rgba = bridge.read_point_colors(capsule.data)
    assert rgba[:, :3].std(axis=0).max() > 0.05, "stress layer is flat"


_MAKE_CAPSULE = """
import json, os, bpy
data = json.load(open(os.environ["OSTEON_TEST_CAPSULE"]))
for o in list(bpy.data.objects):
    bpy.data.objects.remove(o, do_unlink=True)
me = bpy.data.meshes.new("capsule")
me.from_pydata(data["v"], [], data["f"])
me.update()
obj = bpy.data.objects.new("capsule", me)
bpy.context.collection.objects.link(obj)
"""


def _blender():
    return bpy.app.binary_path or shutil.which("blender")


@pytest.mark.skipif(not _blender(), reason="no Blender binary to run the batch command with")
def test_batch_command_auto_skeleton(tmp_path):
    """The headless command: ``blender -b --python batch.py -- --auto-skeleton --report r.json``
    on a scene with one unrigged mesh rigs it, analyses it and exits 0; without a mesh to rig it
    exits non-zero with the reason."""
    from conftest import ROOT, blender_env

    batch_py = os.path.join(ROOT, "blender_addon", "osteon_blender", "batch.py")
    v, f = _capsule()
    spec = tmp_path / "capsule.json"
    spec.write_text(json.dumps({"v": np.asarray(v).tolist(), "f": [list(x) for x in f]}))
    make = tmp_path / "make_capsule.py"
    make.write_text(_MAKE_CAPSULE)
    env = blender_env(OSTEON_TEST_CAPSULE=str(spec))
    rep = tmp_path / "r.json"
    ok = subprocess.run([_blender(), "-b", "--factory-startup", "--python", str(make),
                         "--python", batch_py, "--", "--auto-skeleton", "--report", str(rep),
                         "--print-size", "40", "--force", "80"],
                        check=False, capture_output=True, text=True, env=env, timeout=600)
    assert ok.returncode == 0, ok.stdout[-2000:] + ok.stderr[-2000:]
    assert "skeleton made by osteon.auto_skeleton" in ok.stdout
    data = json.loads(rep.read_text())
    assert data["sections"] > 10 and data["max_stress_mpa"] > 0
    # nothing to rig: the factory scene's cube is removed and no mesh is left
    empty = tmp_path / "empty.py"
    empty.write_text("import bpy\nfor o in list(bpy.data.objects):\n"
                     "    bpy.data.objects.remove(o, do_unlink=True)\n")
    bad = subprocess.run([_blender(), "-b", "--factory-startup", "--python", str(empty),
                          "--python", batch_py, "--", "--auto-skeleton", "--report",
                          str(tmp_path / "bad.json")],
                         check=False, capture_output=True, text=True, env=env, timeout=300)
    assert bad.returncode != 0
    assert "no mesh without an Armature modifier" in bad.stderr
    assert not (tmp_path / "bad.json").exists()
