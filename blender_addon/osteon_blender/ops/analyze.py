import bpy

from .. import service
from ._base import OsteonJobOperator


class OSTEON_OT_analyze(OsteonJobOperator, bpy.types.Operator):
    """Analyse the active rigged mesh: stress (MPa) at every bone section, written to the
    'osteon_stress' colour attribute (blue = 0 MPa, red = allowable stress, grey = surely safe).
    Shows its progress in the status bar; Esc cancels"""

    bl_idname = "osteon.analyze"
    bl_label = "Analyze"

    def steps(self, job):
        return service.analyze_steps(job)

    def finished(self, report: dict) -> str:
        return service.summary(report)
