"""Sidebar sub-panel "Live" under the Osteon panel: Live toggle, throttle, overlay toggle
and a readout of the last live analysis (max stress, allowable, weakest bone)."""

import bpy

from .. import live


class OSTEON_PT_live(bpy.types.Panel):
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Osteon"
    bl_label = "Live"
    bl_parent_id = "OSTEON_PT_main"

    def draw_header(self, context):
        s = getattr(context.scene, "osteon_live", None)
        if s is not None:
            self.layout.prop(s, "enabled", text="")

    def draw(self, context):
        layout = self.layout
        s = getattr(context.scene, "osteon_live", None)
        if s is None:
            layout.label(text="osteon live is not registered", icon="ERROR")
            return
        row = layout.row(align=True)
        on = s.enabled
        row.prop(s, "enabled", text="Live: on" if on else "Live: off", toggle=True,
                 icon="PAUSE" if on else "PLAY")
        col = layout.column(align=True)
        col.prop(s, "throttle_ms")
        col.prop(s, "show_sections", icon="MOD_WIREFRAME")
        r = live.readout(context.scene)
        box = layout.box()
        col = box.column(align=True)
        if r.status.startswith("error"):
            col.label(text=r.status, icon="ERROR")
        elif r.status.startswith("paused"):
            col.label(text=r.status, icon="PAUSE")
        if r.updates == 0:
            col.label(text="No live result yet")
            return
        ratio = r.max_stress_mpa / r.allowable_mpa if r.allowable_mpa > 0 else 0.0
        col.label(text=f"Max stress: {r.max_stress_mpa:.1f} MPa",
                  icon="ERROR" if ratio > 1.0 else "CHECKMARK")
        col.label(text=f"Allowable: {r.allowable_mpa:.1f} MPa")
        if r.weakest_bone:
            col.label(text=f"Weakest bone: {r.weakest_bone} (x{r.weakest_ratio:.2f})",
                      icon="BONE_DATA")
        col.label(text=f"{r.sections} sections, {r.weak_sections} weak")
        col.label(text=f"Update {r.last_update_ms:.0f} ms (analysis {r.analysis_ms:.0f} ms), "
                  f"#{r.updates}")


classes = (OSTEON_PT_live,)
