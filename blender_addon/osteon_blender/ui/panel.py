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
from . import doubt_ui, print_panel

LABEL_SPLIT = 0.35    # share of a labelled dropdown's row its label gets
DEFAULT_WIDTH = 229   # px, the sidebar's default width at UI scale 1 (no region: headless)
MARGINS = 54          # px at UI scale 1: tabs, panel borders and insets of the sidebar
BOX_INSET = 12        # px at UI scale 1: a box's own borders
LOOSE_OP = "OSTEON_OT_select_loose_pieces"   # from branch i12c (ops/loose.py), when present


def labelled(layout, data, prop: str, label: str, search=None):
    """A dropdown (or a search field: ``search`` = (data, collection name)) with its short
    label in front, the way ``use_property_split`` draws, at a width that keeps both legible."""
    split = layout.split(factor=LABEL_SPLIT, align=True)
    split.label(text=label)
    if search is not None:
        split.prop_search(data, prop, search[0], search[1], text="")
    else:
        split.prop(data, prop, text="")


def text_width_px(context) -> float:
    """Width (px) a label has in this sidebar (the region's, or the default headless)."""
    region = getattr(context, "region", None)
    width = region.width if region is not None and region.type == "UI" else DEFAULT_WIDTH
    return width - MARGINS * _scale(context)


def _scale(context) -> float:
    prefs = context.preferences
    scale = float(prefs.system.ui_scale)
    return scale if scale > 0 else float(prefs.view.ui_scale)


def wrap(text: str, width_px: float, scale: float, icon: bool = False) -> list[str]:
    """``text`` cut at spaces into lines no wider than ``width_px`` in the UI font."""
    import blf

    blf.size(0, 11.0 * scale)
    room = width_px - (12.0 + (20.0 if icon else 0.0)) * scale
    lines, cur = [], ""
    for word in text.split():
        trial = f"{cur} {word}" if cur else word
        if cur and blf.dimensions(0, trial)[0] > room:
            lines.append(cur)
            cur = word
        else:
            cur = trial
    if cur:
        lines.append(cur)
    return lines or [""]


def wrapped_label(layout, context, text: str, icon: str = "NONE", inset: float = 0.0) -> None:
    """``text`` as labels cut to the sidebar's width (``inset`` px at UI scale 1 narrower,
    e.g. inside a box); the first line carries ``icon``."""
    col = layout.column(align=True)
    has_icon = icon not in ("NONE", "")
    room = text_width_px(context) - inset * _scale(context)
    for i, line in enumerate(wrap(text, room, _scale(context), has_icon)):
        col.label(text=line, icon=icon if i == 0 else ("BLANK1" if has_icon else "NONE"))


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


class OSTEON_UL_weak_bones(bpy.types.UIList):
    """Result rows: bone (a button that shows it; its tooltip has the full name and numbers),
    stress / allowable, and the cross-section scale Correct gave it."""

    COLUMNS = (0.46,)   # the bone's share; the ratio and the scale share the rest

    def draw_item(self, context, layout, data, item, icon, active_data, active_propname, index):
        split = layout.split(factor=OSTEON_UL_weak_bones.COLUMNS[0], align=True)
        uncut = item.status == "not analysed"
        icon = "QUESTION" if uncut else "ERROR" if item.weak else "CHECKMARK"
        cell = split.row()
        cell.alignment = "LEFT"            # the name reads from the left, like a label
        op = cell.operator("osteon.select_bone", text=item.name, icon=icon, emboss=False)
        op.bone = item.name
        if uncut:
            split.label(text="?")
            split.label(text="")
            return
        col = split.row()
        col.alert = item.weak
        corner = item.stress_concentration > 1.0  # the peak at a corner (docs/notch.md)
        col.label(text=f"{item.ratio:.2f}" + (" K" if corner else ""))
        scaled = abs(item.scale - 1.0) > 1e-6
        split.label(text=f"{item.scale:.2f}" if scaled else "-")


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
        head = layout.split(factor=OSTEON_UL_weak_bones.COLUMNS[0], align=True)
        head.label(text="Bone")
        head.label(text="σ/[σ]")
        head.label(text="Scale")
        layout.template_list("OSTEON_UL_weak_bones", "", s, "weak_bones", s, "weak_bones_index",
                             rows=4)
        row = layout.row(align=True)
        row.operator("osteon.next_weak_bone", icon="FORWARD")
        st = state.get(context.scene)
        rep = st.last["report"] if st is not None and st.last else None
        if rep and rep.get("loose_pieces") and hasattr(bpy.types, LOOSE_OP):
            layout.operator("osteon.select_loose_pieces", icon="STICKY_UVS_DISABLE")


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


classes = (OSTEON_UL_weak_bones, OSTEON_PT_main, OSTEON_PT_results, OSTEON_PT_material,
           OSTEON_PT_load, OSTEON_PT_print, OSTEON_PT_correction)
