"""Export for slicer (3MF), issue 32: on the sample rig under a load that makes it weak, the
operator shows one closed wireframe modifier per reinforced region and writes a PrusaSlicer
project whose modifier volumes carry those regions' walls and infill."""

import xml.etree.ElementTree as ET
import zipfile

import bpy
import numpy as np
from osteon_blender import bridge


def _closed(mesh) -> bool:
    """Every edge of the mesh is shared by exactly two faces."""
    count = {}
    for p in mesh.polygons:
        vs = list(p.vertices)
        for a, b in zip(vs, vs[1:] + vs[:1]):
            key = (min(a, b), max(a, b))
            count[key] = count.get(key, 0) + 1
    return bool(count) and all(c == 2 for c in count.values())


def test_export_for_slicer_shows_the_modifiers_and_writes_them(sample, tmp_path):
    obj, _arm = sample
    s = bpy.context.scene.osteon
    s.material = "PLA"
    s.force_n = 60.0  # weak somewhere once printed with walls and sparse infill
    s.print_settings.profile = "prusaslicer"
    path = tmp_path / "sample.3mf"
    assert bpy.ops.osteon.export_slicer(filepath=str(path), slicer="prusaslicer") == {"FINISHED"}
    shown = list(bpy.data.collections[bridge.MODIFIER_COLLECTION].objects)
    assert shown, "no weak region under 60 N"
    for o in shown:
        assert o.display_type == "WIRE" and _closed(o.data)
        assert o["osteon_perimeters"] >= 2
    with zipfile.ZipFile(path) as z:
        cfg = ET.fromstring(z.read("Metadata/Slic3r_PE_model.config"))
    vols = cfg.find("object").findall("volume")
    meta = [{m.get("key"): m.get("value") for m in v.findall("metadata")} for v in vols]
    mods = [m for m in meta if m.get("modifier") == "1"]
    assert len(mods) == len(shown)
    walls = sorted(int(m["perimeters"]) for m in mods)
    assert walls == sorted(int(o["osteon_perimeters"]) for o in shown)
    # the modifiers were shown where the model is (scene units), not at the bed
    lo = np.min([np.array(o.bound_box).min(0) for o in shown], axis=0)
    hi = np.max([np.array(o.bound_box).max(0) for o in shown], axis=0)
    olo, ohi = np.array(obj.bound_box).min(0), np.array(obj.bound_box).max(0)
    size = float(np.max(ohi - olo))
    assert np.all(lo > olo - 0.2 * size) and np.all(hi < ohi + 0.2 * size)


def test_correct_reinforce_first_thickens_fewer_bones(sample):
    """At 20 N in PLA, printed with PrusaSlicer's 2 walls and 15 % gyroid: plain Correct
    thickens six bones; with Reinforce first only those even solid cannot carry are thickened
    (the rest get walls), and nothing is weak after."""
    from osteon_blender import state

    s = bpy.context.scene.osteon
    s.material = "PLA"
    s.print_settings.profile = "prusaslicer"
    assert bpy.ops.osteon.correct() == {"FINISHED"}
    plain = state.of(bpy.context.scene).last["report"]
    assert plain["reinforcement"] is None
    s.reinforce_first = True
    assert bpy.ops.osteon.correct() == {"FINISHED"}  # starts again from the user's pose
    report = state.of(bpy.context.scene).last["report"]
    block = report["reinforcement"]
    scaled, scaled_plain = set(report["correction"]["bone_scale"]), set(
        plain["correction"]["bone_scale"])
    assert scaled < scaled_plain  # fewer bones thickened
    walls_only = {g["bone"] for g in block["regions"]} - scaled
    # a region that walls and infill cannot fix is reported unfixable, by bone (corners at the
    # print's resolution, docs/notch.md "Limits", can outlast walls, infill and thickening)
    assert walls_only
    print("REGIONS", [(g["bone"], g["fixed"]) for g in block["regions"]],
          "UNFIXABLE", sorted({u["bone"] for u in block["unfixable"]}), "SCALED", sorted(scaled))
    assert {g["bone"] for g in block["regions"] if not g["fixed"]} <= \
        {u["bone"] for u in block["unfixable"]}
    shown = bpy.data.collections[bridge.MODIFIER_COLLECTION].objects
    assert len(shown) == len(block["regions"])
