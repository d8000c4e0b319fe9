"""Sidebar sub-panel "Live" under the Osteon panel: one Live on/off button, the throttle, the
overlay's options (Show sections, All sections) and a readout of the last live analysis (the
governing section in the summary's words: stress / allowable, both in MPa, and which allowable;
the panel's summary and rows show the same result while Live runs)."""

import bpy

from .. import live, results
from .widgets import BOX_INSET, wrapped_label


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
        if r.weakest_bone:   # the governing section, in the summary's words (results.py)
            wrapped_label(col, context, results.worst_line(
                r.weakest_bone, r.worst_stress_mpa, r.worst_allowable_mpa, r.weakest_ratio,
                r.worst_limit), "ERROR" if r.weakest_ratio >= 1.0 else "CHECKMARK",
                inset=BOX_INSET)
        col.label(text=f"{r.weak_sections} of {r.sections} sections over")
        col.label(text=f"{r.last_update_ms:.0f} ms ({r.analysis_ms:.0f} analysis), #{r.updates}")


classes = (OSTEON_PT_live,)
