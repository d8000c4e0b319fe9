"""Fixtures for the add-on tests, run inside real Blender:

* Debian's Blender 3.4.1:  blender -b --factory-startup --python-exit-code 1 \
      --python tests/blender/run_in_blender.py -- tests/blender
* the bpy 4.5 wheel:       .venv-bpy/bin/python -m pytest tests/blender

See scripts/blender_tests.sh, which wires both.
"""

from __future__ import annotations

import os
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
for p in (os.path.join(ROOT, "blender_addon"),):
    if p not in sys.path:
        sys.path.insert(0, p)

# Importing bpy 5.2 sets OCIO (its own colour config) in the C environment, which the child
# inherits and which makes Debian's Blender 3.4.1 abort: child Blenders get blender_env().
_OCIO_BEFORE = os.environ.get("OCIO")
bpy = pytest.importorskip("bpy")


def blender_env(**extra) -> dict:
    """Environment for a child Blender process: os.environ without an OCIO that importing
    bpy set (a user's own OCIO is kept), plus ``extra``."""
    env = dict(os.environ, **extra)
    if _OCIO_BEFORE is None:
        env.pop("OCIO", None)
    else:
        env["OCIO"] = _OCIO_BEFORE
    return env

# test models live in the repository (tests/data/SOURCES.md); OSTEON_DATA may override
DATA = os.environ.get("OSTEON_DATA", os.path.join(ROOT, "tests", "data"))


@pytest.fixture(scope="session")
def addon():
    import osteon_blender

    if not hasattr(bpy.types.Scene, "osteon"):
        osteon_blender.register()
    yield osteon_blender
    if hasattr(bpy.types.Scene, "osteon"):
        osteon_blender.unregister()


@pytest.fixture(scope="session")
def engine():
    """The real osteon engine (tests that need it fail loudly when it is missing)."""
    import osteon

    return osteon


def empty_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    return bpy.context.scene


@pytest.fixture
def sample(addon):
    """A fresh scene with the bundled sample figurine (mesh active), default settings."""
    from osteon_blender import sample as sample_rig

    empty_scene()
    obj, arm = sample_rig.build()
    return obj, arm


def import_rignet(model: str):
    """Import a RigNet FBX from tests/data into an empty scene -> (mesh, armature)."""
    import addon_utils

    path = os.path.join(DATA, "RigNet", f"{model}_ori.fbx")
    if not os.path.isfile(path):
        pytest.fail(f"missing test data {path}")
    empty_scene()
    addon_utils.enable("io_scene_fbx", default_set=True)
    bpy.ops.import_scene.fbx(filepath=path)
    meshes = [o for o in bpy.context.scene.objects if o.type == "MESH"]
    arms = [o for o in bpy.context.scene.objects if o.type == "ARMATURE"]
    assert len(meshes) == 1 and len(arms) == 1
    return meshes[0], arms[0]


def activate(obj):
    vl = bpy.context.view_layer
    for o in bpy.context.scene.objects:
        o.select_set(False)
    if obj is not None:
        obj.select_set(True)
    vl.objects.active = obj


def one_bone_rig(name, vertices, faces, bone, head, tail):
    """A mesh object `name` (from_pydata) bound whole to an armature "rig" of one bone `bone`
    (head, tail in Blender units) by a vertex group and an Armature modifier; the mesh active."""
    me = bpy.data.meshes.new(name)
    me.from_pydata(vertices, [], faces)
    me.update()
    obj = bpy.data.objects.new(name, me)
    bpy.context.scene.collection.objects.link(obj)
    ad = bpy.data.armatures.new("rig")
    arm = bpy.data.objects.new("rig", ad)
    bpy.context.scene.collection.objects.link(arm)
    activate(arm)
    bpy.ops.object.mode_set(mode="EDIT")
    b = ad.edit_bones.new(bone)
    b.head, b.tail = head, tail
    bpy.ops.object.mode_set(mode="OBJECT")
    obj.vertex_groups.new(name=bone).add(list(range(len(vertices))), 1.0, "REPLACE")
    obj.modifiers.new("Armature", "ARMATURE").object = arm
    activate(obj)
    return obj, arm


def run_op(op, capfd) -> tuple[set, str]:
    """Call an operator; return (result set, the report text Blender printed)."""
    capfd.readouterr()
    result = op()
    out, err = capfd.readouterr()
    return result, out + err
