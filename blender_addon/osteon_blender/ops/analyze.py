import bpy

from .. import service
from ._base import OsteonOperator


class OSTEON_OT_analyze(OsteonOperator, bpy.types.Operator):
    """Analyse the active rigged mesh: stress (MPa) at every bone section, written to the
    'osteon_stress' colour attribute (blue = 0 MPa, red = allowable stress, grey = surely safe)"""

    bl_idname = "osteon.analyze"
    bl_label = "Analyze"

    def run(self, context):
        return service.summary(service.run_analyze(context, progress=self.progress))
