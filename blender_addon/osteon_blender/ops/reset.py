import bpy

from .. import bridge, service
from ._base import OsteonOperator


class OSTEON_OT_reset(OsteonOperator, bpy.types.Operator):
    """Restore the pose-bone scales changed by Correct, remove the osteon_stress layer and put
    back the viewport shading colour Analyze switched to the attribute"""

    bl_idname = "osteon.reset"
    bl_label = "Reset"

    def run(self, context):
        changed = service.run_reset(context)
        shading = bridge.restore_viewport_colors()
        return "osteon: restored" if changed or shading else "osteon: nothing to reset"
