import bpy

from .. import service
from ._base import OsteonOperator


class OSTEON_OT_apply(OsteonOperator, bpy.types.Operator):
    """Bake the correction into the mesh: thicken the rest shape, then restore the pose scales.
    This is the only osteon action that modifies the mesh data"""

    bl_idname = "osteon.apply"
    bl_label = "Apply Correction to Mesh"

    def invoke(self, context, event):
        return context.window_manager.invoke_confirm(self, event)

    def run(self, context):
        report = service.run_apply(context)
        # service.summary starts with "osteon: " itself
        return "osteon: correction applied to the mesh; " + service.summary(report).removeprefix(
            "osteon: ")
