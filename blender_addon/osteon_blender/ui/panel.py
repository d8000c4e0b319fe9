"""The N-sidebar tab "Osteon" and the weak-bone list."""

import bpy

from .. import bridge, core
from . import doubt_ui, print_panel


class OSTEON_UL_weak_bones(bpy.types.UIList):
    def draw_item(self, context, layout, data, item, icon, active_data, active_propname, index):
        row = layout.row(align=True)
        if item.status == "not analysed":  # osteon.doubt: never shown as safe
            row.label(text=item.name, icon="QUESTION")
            row.label(text="not analysed")
            row.label(text=item.reason)
            return
        row.label(text=item.name, icon="ERROR" if item.weak else "CHECKMARK")
        row.label(text=f"{item.max_stress_mpa:.1f} MPa")
        row.label(text=f"x{item.ratio:.2f}")
        if item.limit and context.scene.osteon.layer_strength_ratio != 1.0:
            row.label(text=item.limit)
        if abs(item.scale - 1.0) > 1e-6:
            row.label(text=f"scale {item.scale:.2f}")


class OSTEON_PT_main(bpy.types.Panel):
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Osteon"
    bl_label = "Osteon"

    def draw(self, context):
        layout = self.layout
        s = context.scene.osteon
        col = layout.column(align=True)
        col.prop(s, "material")
        col.prop(s, "strength_mpa")
        col.prop(s, "safety_factor")
        try:
            col.label(text=f"Allowable: {core.allowable_stress(s.strength_mpa, s.safety_factor):.1f}"
                      " MPa")
        except ValueError:
            col.label(text="Allowable: invalid", icon="ERROR")
        print_panel.draw(layout, s)
        col = layout.column(align=True)
        col.prop(s, "force_n")
        col.prop(s, "size_mode", text="")
        if s.size_mode != "UNITS":
            col.prop(s, "print_size_mm")
        col.prop(s, "interval_mm")
        arm = None
        ob = context.active_object
        if ob is not None:
            arm = ob if ob.type == "ARMATURE" else bridge.armature_of(ob) if ob.type == "MESH" else None
        if arm is not None:
            col.prop_search(s, "held_bone", arm.data, "bones")
        else:
            col.prop(s, "held_bone")
        if ob is not None and ob.type == "MESH" and arm is None:
            layout.operator("osteon.make_skeleton", icon="ARMATURE_DATA")
        row = layout.row(align=True)
        row.scale_y = 1.3
        row.operator("osteon.analyze", icon="VIEWZOOM")
        row.operator("osteon.correct", icon="MOD_SOLIDIFY")
        row.operator("osteon.reset", icon="LOOP_BACK")
        sub = layout.column(align=True)
        sub.prop(s, "scaling")
        sub.prop(s, "max_scale")
        sub.prop(s, "max_rounds")
        if s.has_result:
            box = layout.box()
            box.label(text=f"{s.result_object}: max {s.max_stress_mpa:.1f} / "
                      f"{s.allowable_mpa:.1f} MPa")
            box.label(text=f"{s.sections} sections, {s.weak_sections} weak")
            doubt_ui.draw_doubt(box, s)
            if len(s.weak_bones):
                box.template_list("OSTEON_UL_weak_bones", "", s, "weak_bones", s,
                                  "weak_bones_index", rows=4)
            elif s.verdict == "ok":
                box.label(text="No weak bones", icon="CHECKMARK")
            if arm is not None and bridge.has_saved_pose(arm):
                box.operator("osteon.apply", icon="CHECKMARK")


classes = (OSTEON_UL_weak_bones, OSTEON_PT_main)
