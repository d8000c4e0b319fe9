"""The "Print settings" sub-panel: how the part is printed (walls, skins, infill; issue 31,
docs/printing.md), stored on ``scene.osteon.print_settings`` and mapped through the wheel's
``osteon.settings.Settings`` (``printprofile.settings_fields``)."""

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty

from .. import printprofile


def _on_profile(self, _context):
    """A new preset (or "Change settings" switched on): the fields start from its numbers."""
    for prop, value in printprofile.preset_values(self.profile).items():
        setattr(self, prop, value)


class OsteonPrintSettings(bpy.types.PropertyGroup):
    profile: EnumProperty(
        name="Profile", items=printprofile.PROFILE_ITEMS, default="solid", update=_on_profile,
        description="How the part is printed: a slicer's default walls, skins and infill, a "
        "hollowed resin print, or solid (the section as cut; the default)")
    customize: BoolProperty(
        name="Change settings", default=False, update=_on_profile,
        description="Change the preset's numbers (they start from the preset's)")
    perimeters: IntProperty(name="Perimeters", default=2, min=0, max=100,
                            description="Wall loops per layer")
    infill_percent: FloatProperty(name="Infill", default=15.0, min=0.0, max=100.0,
                                  subtype="PERCENTAGE", precision=0,
                                  description="Sparse infill density, percent")
    pattern: EnumProperty(name="Pattern", items=printprofile.PATTERN_ITEMS, default="gyroid",
                          description="Infill pattern")
    line_width_mm: FloatProperty(name="Line width (mm)", default=0.45, min=0.01, soft_max=2.0,
                                 precision=2, description="Perimeter extrusion width, mm")
    layer_height_mm: FloatProperty(name="Layer height (mm)", default=0.2, min=0.01,
                                   soft_max=1.0, precision=2, description="Layer height, mm")
    top_bottom_layers: IntProperty(name="Top/bottom layers", default=4, min=0, max=1000,
                                   description="Solid layers at the top and bottom surfaces")
    shell_mm: FloatProperty(name="Shell (mm)", default=2.0, min=0.01, soft_max=20.0,
                            precision=2, description="Shell thickness of a hollowed resin "
                            "print, mm")


class OSTEON_PT_print_settings(bpy.types.Panel):
    """Walls, skins and infill as the slicer prints them: the printed section"""

    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Osteon"
    bl_parent_id = "OSTEON_PT_main"
    bl_label = "Print settings"
    bl_options = {"DEFAULT_CLOSED"}  # noqa: RUF012

    def draw(self, context):
        layout = self.layout
        s = context.scene.osteon
        ps = s.print_settings
        from .panel import wrapped_label

        layout.prop(ps, "profile", text="")
        wrapped_label(layout, context, printprofile.summary(ps.profile))
        hint = printprofile.suggested(s.material)
        if hint and hint != ps.profile:
            wrapped_label(layout, context, f"{s.material} suggests: {hint}")
        kind = printprofile.profiles.get_profile(ps.profile).kind
        if kind == "solid":
            return
        layout.prop(ps, "customize")
        if not ps.customize:
            return
        col = layout.column(align=True)
        for prop, (_field, k, _convert) in printprofile.FIELDS.items():
            if k == kind:
                col.prop(ps, prop)


property_classes = (OsteonPrintSettings,)
panel_classes = (OSTEON_PT_print_settings,)
