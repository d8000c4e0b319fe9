"""The add-on's preferences (Edit > Preferences > Add-ons > Osteon): the section guard."""

from __future__ import annotations

import bpy
from osteon.settings import SECTION_LIMIT


class OsteonPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    max_sections: bpy.props.IntProperty(
        name="Section limit",
        description=("Analyze and Correct ask before making more sections than this (a model "
                     "in metres read as mm, a tiny section interval); 0 = never ask"),
        default=SECTION_LIMIT, min=0,
    )

    def draw(self, _context):
        self.layout.prop(self, "max_sections")


def max_sections(context) -> int:
    """The guard's limit: the preference, or the wheel's default when the add-on was registered
    without its preferences (scripts that call ``register()`` themselves)."""
    addon = context.preferences.addons.get(__package__)
    prefs = getattr(addon, "preferences", None)
    return int(getattr(prefs, "max_sections", SECTION_LIMIT))


classes = (OsteonPreferences,)
