"""The N-sidebar tab "Osteon": the main panel (the three buttons and the verdict) and its
sub-panels Results, Material, Load, Print direction and Correction (the Live sub-panel is
live_panel.py).  Laid out for the default sidebar width (229 px at UI scale 1): short labels
with the unit in the name ("Force (N)") or the tooltip, the dropdowns' labels in a split of
their own, long texts wrapped to the region's width; ``scripts/ui_screenshots.py`` checks in a
real window that every text fits.  No panel polls itself away and no line appears or goes
between two redraws of the same result, so Blender never animates the panels over each
other."""

from __future__ import annotations

import bpy

from .. import bridge, core, state
from . import doubt_ui, print_panel, widgets
from .widgets import BOX_INSET, labelled, wrapped_label

LOOSE_OP = "OSTEON_OT_select_loose_pieces"   # from branch i12c (ops/loose.py), when present


def summary(s) -> list[str]:
    """The summary's texts, verdict first (the screenshot check reads the first)."""
    return [t for t, _icon in doubt_ui.summary_lines(s)]


def target_armature(context):
    ob = context.active_object
    if ob is None:
        return None, None
    if ob.type == "ARMATURE":
        return ob, ob
    return ob, bridge.armature_of(ob) if ob.type == "MESH" else None


class _Sub:
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Osteon"
    bl_parent_id = "OSTEON_PT_main"


#: px at UI scale 1 of each number column of the result rows ("2.08", "33.6", "1.45"); a
#: UIList row loses LIST_MARGIN px to the list's box and scroll bar (tests/blender/ui_fit.py)
NUMBER_COLUMN = 38
LIST_MARGIN = 26
SUBPANEL_INSET = 4    # px at UI scale 1: a sub-panel's layout is this much narrower


def _scaled_rows(s) -> bool:
    return any(abs(r.scale - 1.0) > 1e-6 for r in s.weak_bones)


def row_columns(context, s) -> tuple[float, float, int]:
    """(name share of a result row, its width in px, number of number columns): the name
    gets what the fixed narrow number columns leave (stress / allowable, and the scale once
    Correct has scaled a bone). The list lives in the Results sub-panel: its indent counts."""
    scale = widgets._scale(context)
    width = widgets.text_width_px(context) - (LIST_MARGIN + widgets.SUBPANEL_INDENT) * scale
    ncols = 2 if _scaled_rows(s) else 1
    numbers = ncols * NUMBER_COLUMN * scale
    share = max(0.3, min(0.85, 1.0 - numbers / max(width, 1.0)))
    return share, width * share, ncols


def _ratio_text(ratio: float) -> str:
    """At most four characters: 0.99, 2.08, 33.6, 336."""
    return f"{ratio:.2f}" if ratio < 9.995 else f"{ratio:.1f}" if ratio < 99.95 else f"{ratio:.0f}"


class OSTEON_UL_weak_bones(bpy.types.UIList):
    """Result rows: the bone's name first (a button that shows it; its tooltip has the full
    name, the stress and the allowable that governs), then fixed narrow columns: stress /
    allowable at its governing section and, after Correct, the cross-section scale."""

    def draw_item(self, context, layout, data, item, icon, active_data, active_propname, index):
        share, name_px, ncols = row_columns(context, data)
        split = layout.split(factor=share, align=True)
        uncut = item.status == "not analysed"
        cell = split.row()
        cell.alignment = "LEFT"            # the name reads from the left, like a label
        # "K " before the name: the ratio includes a corner's stress concentration (docs/notch.md;
        # the tooltip says so); in the name cell, whose text is fitted, so the numbers keep
        # their narrow fixed column
        corner = item.stress_concentration > 1.0
        name = widgets.fit_text(("K " if corner else "") + item.name, name_px,
                                widgets._scale(context))
        op = cell.operator("osteon.select_bone", text=name, emboss=False)
        op.bone = item.name
        nums = split.split(factor=1.0 / ncols, align=True) if ncols > 1 else split.row()
        if uncut:
            nums.label(text="?", icon="NONE")
            if ncols > 1:
                nums.label(text="")
            return
        col = nums.row()
        col.alert = item.weak
        col.label(text=_ratio_text(item.ratio))
        if ncols > 1:
            scaled = abs(item.scale - 1.0) > 1e-6
            nums.label(text=f"{item.scale:.2f}" if scaled else "-")


class OSTEON_PT_main(bpy.types.Panel):
    """Analyze / Correct / Reset and the verdict of the last result"""

    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Osteon"
    bl_label = "Osteon"

    def draw(self, context):
        layout = self.layout
        s = context.scene.osteon
        ob, arm = target_armature(context)
        col = layout.column(align=True)
        row = col.row(align=True)
        row.scale_y = 1.3
        row.operator("osteon.analyze", icon="VIEWZOOM")
        row = col.row(align=True)
        row.operator("osteon.correct", icon="MOD_SOLIDIFY")
        row.operator("osteon.reset", icon="LOOP_BACK")
        if ob is not None and ob.type == "MESH" and arm is None:
            layout.operator("osteon.make_skeleton", icon="ARMATURE_DATA")
        col = layout.box().column(align=True)
        for text, icon in doubt_ui.summary_lines(s):
            wrapped_label(col, context, text, icon, inset=BOX_INSET)
        if arm is not None and bridge.has_saved_pose(arm):
            layout.operator("osteon.apply", icon="CHECKMARK")


class OSTEON_PT_results(_Sub, bpy.types.Panel):
    """The bones over the limit (and those not analysed): click one to see where it is"""

    bl_label = "Results"

    def draw(self, context):
        layout = self.layout
        s = context.scene.osteon
        if not len(s.weak_bones):
            layout.label(text="No bone over the limit" if s.has_result else "No result yet")
            return
        share, _px, ncols = row_columns(context, s)
        head = layout.split(factor=share, align=True)
        head.label(text="Bone")
        nums = head.split(factor=1.0 / ncols, align=True) if ncols > 1 else head.row()
        nums.label(text="σ/[σ]")
        if ncols > 1:
            nums.label(text="Scale")
        layout.template_list("OSTEON_UL_weak_bones", "", s, "weak_bones", s, "weak_bones_index",
                             rows=4)
        row = layout.row(align=True)
        row.operator("osteon.next_weak_bone", icon="FORWARD")
        st = state.get(context.scene)
        rep = st.last["report"] if st is not None and st.last else None
        if rep and rep.get("loose_pieces") and hasattr(bpy.types, LOOSE_OP):
            layout.operator("osteon.select_loose_pieces", icon="STICKY_UVS_DISABLE")


class OSTEON_PT_colours(_Sub, bpy.types.Panel):
    """What the stress colours on the mesh mean: stress / allowable at each part (the same
    ratio as the summary and the rows), grey and magenta"""

    bl_label = "Colour scale"

    def draw(self, context):
        col = self.layout.column(align=True)
        for _rgba, icon, text in core.LEGEND:
            wrapped_label(col, context, text, icon, inset=SUBPANEL_INSET)


class OSTEON_PT_material(_Sub, bpy.types.Panel):
    """Material preset, strength (MPa) and safety factor: the allowable stress"""

    bl_label = "Material"

    def draw(self, context):
        layout = self.layout
        s = context.scene.osteon
        labelled(layout, s, "material", "Material")
        col = layout.column(align=True)
        col.prop(s, "strength_mpa")
        col.prop(s, "safety_factor")
        try:
            allowable = core.allowable_stress(s.strength_mpa, s.safety_factor)
            layout.label(text=f"Allowable {allowable:.1f} MPa")
        except ValueError:
            layout.label(text="Allowable: invalid", icon="ERROR")


class OSTEON_PT_load(_Sub, bpy.types.Panel):
    """The force (N), the printed size (mm), the section interval (mm), junction cores, the
    held bone"""

    bl_label = "Load"

    def draw(self, context):
        layout = self.layout
        s = context.scene.osteon
        col = layout.column(align=True)
        col.prop(s, "force_n")
        col.prop(s, "interval_mm")
        col.prop(s, "junction_cores")
        col = layout.column(align=True)
        col.prop(s, "size_mode", text="")
        if s.size_mode != "UNITS":
            col.prop(s, "print_size_mm")
        _ob, arm = target_armature(context)
        if arm is not None:
            labelled(layout, s, "held_bone", "Held", search=(arm.data, "bones"))
        else:
            labelled(layout, s, "held_bone", "Held")


class OSTEON_PT_print(_Sub, bpy.types.Panel):
    """FDM layers: their strength across, the build direction, the best orientation"""

    bl_label = "Print direction"
    bl_options = {"DEFAULT_CLOSED"}  # noqa: RUF012

    def draw(self, context):
        print_panel.draw(self.layout, context.scene.osteon, context)


class OSTEON_PT_correction(_Sub, bpy.types.Panel):
    """How Correct thickens the weak bones"""

    bl_label = "Correction"
    bl_options = {"DEFAULT_CLOSED"}  # noqa: RUF012

    def draw(self, context):
        layout = self.layout
        s = context.scene.osteon
        labelled(layout, s, "scaling", "Scaling")
        col = layout.column(align=True)
        col.prop(s, "max_scale")
        col.prop(s, "max_rounds")
        layout.prop(s, "reinforce_first")


classes = (OSTEON_UL_weak_bones, OSTEON_PT_main, OSTEON_PT_results, OSTEON_PT_colours,
           OSTEON_PT_material, OSTEON_PT_load, OSTEON_PT_print, OSTEON_PT_correction)
