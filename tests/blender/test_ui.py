"""The sidebar panel and the weak-bone list draw without errors and only name real
properties (drawn against a recording layout: background Blender has no window)."""

import bpy
from conftest import activate


class Recorder:
    """Stands in for bpy's UILayout: records prop()/operator()/label() calls."""

    def __init__(self, log):
        self.log = log
        self.scale_y = 1.0

    def _sub(self, *args, **kwargs):
        return Recorder(self.log)

    row = column = box = split = _sub

    def prop(self, data, name, **kwargs):
        self.log.append(("prop", data, name))

    def prop_search(self, data, name, search_data, search_name, **kwargs):
        self.log.append(("prop", data, name))
        self.log.append(("prop", search_data, search_name))

    def operator(self, idname, **kwargs):
        self.log.append(("operator", idname))

    def label(self, text="", **kwargs):
        self.log.append(("label", text))

    def template_list(self, list_type, list_id, data, prop, active_data, active_prop, **kw):
        self.log.append(("list", list_type))
        self.log.append(("prop", data, prop))
        self.log.append(("prop", active_data, active_prop))


def _draw(context):
    log = []
    panel = bpy.types.OSTEON_PT_main
    fake = type("P", (), {"layout": Recorder(log)})()
    panel.draw(fake, context)
    for entry in log:
        if entry[0] == "prop":
            _, data, name = entry
            assert name in data.bl_rna.properties, name
        if entry[0] == "operator":
            idname = entry[1].split(".")
            assert hasattr(getattr(bpy.ops, idname[0]), idname[1]), entry[1]
    return log


def test_panel_draws_before_and_after_results(sample):
    assert bpy.types.OSTEON_PT_main.bl_category == "Osteon"
    assert bpy.types.OSTEON_PT_main.bl_region_type == "UI"
    log = _draw(bpy.context)
    ops = [e[1] for e in log if e[0] == "operator"]
    main_ops = ("osteon.analyze", "osteon.correct", "osteon.reset")
    assert [o for o in ops if o in main_ops] == list(main_ops)
    assert {"osteon.find_orientation", "osteon.apply_orientation"} <= set(ops)  # Print direction
    assert ("label", "Allowable: 30.0 MPa") in log
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    log = _draw(bpy.context)
    assert ("list", "OSTEON_UL_weak_bones") in log
    assert bpy.ops.osteon.correct() == {"FINISHED"}
    log = _draw(bpy.context)
    assert ("operator", "osteon.apply") in log
    activate(None)
    _draw(bpy.context)


def test_weak_bone_rows_show_stress_and_ratio(sample):
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    s = bpy.context.scene.osteon
    log = []
    ul = bpy.types.OSTEON_UL_weak_bones
    ul.draw_item(None, bpy.context, Recorder(log), s, s.weak_bones[0], 0, s, "weak_bones_index", 0)
    texts = [e[1] for e in log if e[0] == "label"]
    assert texts[0] == s.weak_bones[0].name
    assert texts[1].endswith(" MPa") and texts[2].startswith("x")
    assert float(texts[2][1:]) > 1.0
