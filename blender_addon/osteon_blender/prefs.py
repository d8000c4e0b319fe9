"""The add-on's preferences (Edit > Preferences > Add-ons > Osteon): the section guard and the
documentation (docs/blender.md, shipped inside the add-on by scripts/build_addon.py)."""

from __future__ import annotations

import os

import bpy
from osteon.settings import SECTION_LIMIT

#: the user guide inside the installed add-on (the zips carry it; a checkout has it in docs/)
DOC_FILE = "docs/blender.md"


def doc_path() -> str | None:
    """The add-on's user guide on disk: inside the installed add-on, else the repository's."""
    here = os.path.dirname(os.path.abspath(__file__))
    for root in (here, os.path.dirname(os.path.dirname(here))):
        path = os.path.join(root, *DOC_FILE.split("/"))
        if os.path.isfile(path):
            return path
    return None


class OSTEON_OT_open_docs(bpy.types.Operator):
    """Open the add-on's user guide (docs/blender.md) with the system's viewer"""

    bl_idname = "osteon.open_docs"
    bl_label = "Documentation"
    bl_options = {"INTERNAL"}  # noqa: RUF012

    def execute(self, context):
        path = doc_path()
        if path is None:
            self.report({"ERROR"}, f"The add-on's {DOC_FILE} is missing: reinstall the zip")
            return {"CANCELLED"}
        bpy.ops.wm.path_open(filepath=path)
        self.report({"INFO"}, f"osteon: {path}")
        return {"FINISHED"}


class OsteonPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    max_sections: bpy.props.IntProperty(
        name="Section limit",
        description=("Analyze and Correct ask before making more sections than this (a model "
                     "in metres read as mm, a tiny section interval); 0 = never ask"),
        default=SECTION_LIMIT, min=0,
    )

    def draw(self, _context):
        layout = self.layout
        layout.prop(self, "max_sections")
        row = layout.row()
        row.operator(OSTEON_OT_open_docs.bl_idname, icon="HELP")
        path = doc_path()
        row.label(text=path or f"{DOC_FILE} not found")


def max_sections(context) -> int:
    """The guard's limit: the preference, or the wheel's default when the add-on was registered
    without its preferences (scripts that call ``register()`` themselves)."""
    addon = context.preferences.addons.get(__package__)
    prefs = getattr(addon, "preferences", None)
    return int(getattr(prefs, "max_sections", SECTION_LIMIT))


classes = (OSTEON_OT_open_docs, OsteonPreferences)
