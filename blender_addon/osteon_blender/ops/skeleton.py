"""osteon.make_skeleton: rig a mesh that has no armature (osteon.auto_skeleton, issue 17)."""

import bpy

from .. import service
from ._base import OsteonOperator


class OSTEON_OT_make_skeleton(OsteonOperator, bpy.types.Operator):
    """Build an Armature from the mesh's curve skeleton (osteon.auto_skeleton, needs pygel3d)
    and bind the mesh with vertex groups and an Armature modifier"""

    bl_idname = "osteon.make_skeleton"
    bl_label = "Make skeleton"

    blender_weights: bpy.props.BoolProperty(  # type: ignore[valid-type]
        name="Blender's automatic weights",
        description="Bind with Blender's automatic (bone heat) weights instead of osteon's",
        default=False,
    )
    root: bpy.props.EnumProperty(  # type: ignore[valid-type]
        name="Root",
        items=(("centre", "Centre", "Hold the model at the bone nearest its barycentre"),
               ("base", "Base", "Hold the model at its lowest point (the base it stands on)")),
        default="centre",
    )

    def run(self, context):
        r = service.run_make_skeleton(context, auto_weights=self.blender_weights,
                                      root=self.root, progress=self.progress)
        for text in r["warnings"]:  # loose pieces: the skeleton is made, but say so
            self.report({"WARNING"}, text)
        return (f"osteon: {r['armature']}: {r['bones']} bones in {r['seconds']:.1f} s "
                f"({r['weights']} weights)")
