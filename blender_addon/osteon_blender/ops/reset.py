import bpy

from .. import service
from ._base import OsteonOperator


class OSTEON_OT_reset(OsteonOperator, bpy.types.Operator):
    """Restore the pose-bone scales changed by Correct and remove the osteon_stress layer"""

    bl_idname = "osteon.reset"
    bl_label = "Reset"

    def run(self, context):
        changed = service.run_reset(context)
        return "osteon: restored" if changed else "osteon: nothing to reset"
