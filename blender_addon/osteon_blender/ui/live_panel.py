"""Sidebar sub-panel "Live" under the Osteon panel: one Live on/off button, the throttle, the
overlay's options (Show sections, All sections) and a readout of the last live analysis (max
stress and allowable stress in MPa, the weakest bone)."""

import bpy

from .. import live
from .widgets import wrapped_label


class OSTEON_PT_live(bpy.types.Panel):
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Osteon"
    bl_label = "Live"
    bl_parent_id = "OSTEON_PT_main"

    def draw(self, context):
        layout = self.layout
        s = getattr(context.scene, "osteon_live", None)
        if s is None:
            layout.label(text="Live is not registered", icon="ERROR")
            return
        on = s.enabled
        layout.prop(s, "enabled", text="Live: on" if on else "Live: off", toggle=True,
                    icon="PAUSE" if on else "PLAY")
        layout.prop(s, "throttle_ms")
        col = layout.column(align=True)
        col.prop(s, "show_sections")
        sub = col.row()
        sub.active = s.show_sections
        sub.prop(s, "show_all_sections")
        r = live.readout(context.scene)
        box = layout.box()
        col = box.column(align=True)
        if r.status.startswith(("error", "paused")):
            wrapped_label(col, context, r.status,
                          "ERROR" if r.status.startswith("error") else "PAUSE")
        if r.updates == 0:
            col.label(text="No live result yet")
            return
        ratio = r.max_stress_mpa / r.allowable_mpa if r.allowable_mpa > 0 else 0.0
        col.label(text=f"Max {r.max_stress_mpa:.1f} / {r.allowable_mpa:.1f} MPa",
                  icon="ERROR" if ratio > 1.0 else "CHECKMARK")
        if r.weakest_bone:
            col.label(text=f"Worst x{r.weakest_ratio:.2f}: {r.weakest_bone}", icon="BONE_DATA")
        col.label(text=f"{r.weak_sections} of {r.sections} sections over")
        col.label(text=f"{r.last_update_ms:.0f} ms ({r.analysis_ms:.0f} analysis), #{r.updates}")


classes = (OSTEON_PT_live,)
