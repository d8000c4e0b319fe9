"""Registration: twice in a row, clean unregister, settings with units."""

import ast
import os

import bpy
import osteon_blender

OPS = ("analyze", "correct", "reset", "apply", "select_bone", "next_weak_bone",
       "select_loose_pieces")


def _registered() -> bool:
    return hasattr(bpy.types.Scene, "osteon") and all(
        hasattr(bpy.ops.osteon, name) and getattr(bpy.ops.osteon, name).poll() is not None
        for name in OPS)


def test_register_unregister_twice():
    if hasattr(bpy.types.Scene, "osteon"):
        osteon_blender.unregister()
    for _ in range(2):
        osteon_blender.register()
        assert hasattr(bpy.types.Scene, "osteon")
        assert hasattr(bpy.types, "OSTEON_PT_main")
        assert hasattr(bpy.types, "OSTEON_UL_weak_bones")
        for name in OPS:
            assert getattr(bpy.ops.osteon, name).idname() == f"OSTEON_OT_{name}"
        s = bpy.context.scene.osteon
        assert s.force_n == 20.0 and s.strength_mpa == 60.0 and s.safety_factor == 2.0
        osteon_blender.unregister()
        assert not hasattr(bpy.types.Scene, "osteon")
        assert not hasattr(bpy.types, "OSTEON_PT_main")
    osteon_blender.register()  # leave registered for the other tests (the fixture unregisters)


def test_units_in_every_setting(addon):
    props = bpy.types.Scene.bl_rna.properties["osteon"].fixed_type.properties
    for key, unit in (("force_n", "(N)"), ("strength_mpa", "(MPa)"), ("print_size_mm", "(mm)"),
                      ("interval_mm", "(mm)")):
        assert unit in props[key].name, key


def test_material_preset_sets_strength(addon):
    s = bpy.context.scene.osteon
    s.material = "ABS"
    assert s.strength_mpa == 40.0
    s.material = "PETG"
    assert s.strength_mpa == 50.0
    s.strength_mpa = 33.0  # editable after choosing a preset
    assert s.strength_mpa == 33.0
    s.material = "PLA"
    assert s.strength_mpa == 60.0


def test_operators_are_undoable(addon):
    for name in ("analyze", "correct", "reset", "apply"):
        cls = getattr(bpy.types, f"OSTEON_OT_{name}")
        assert {"REGISTER", "UNDO"} <= set(cls.bl_options), name


def test_bl_info_and_manifest_agree():
    here = os.path.dirname(osteon_blender.__file__)
    with open(os.path.join(here, "__init__.py"), encoding="utf-8") as fh:
        tree = ast.parse(fh.read())
    info = next(ast.literal_eval(n.value) for n in tree.body
                if isinstance(n, ast.Assign) and getattr(n.targets[0], "id", "") == "bl_info")
    assert info["blender"] == (3, 4, 0)
    with open(os.path.join(here, "blender_manifest.toml"), encoding="utf-8") as fh:
        manifest = fh.read()
    version = ".".join(map(str, info["version"]))
    assert f'version = "{version}"' in manifest
    assert 'id = "osteon_blender"' in manifest
