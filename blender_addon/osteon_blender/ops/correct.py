import bpy

from .. import service
from ._base import OsteonOperator


class OSTEON_OT_correct(OsteonOperator, bpy.types.Operator):
    """Thicken weak bones: scale pose bones across their axis (length kept, children keep
    shape and place) until no section exceeds the allowable stress (MPa); Reset undoes it"""

    bl_idname = "osteon.correct"
    bl_label = "Correct"

    def run(self, context):
        report = service.run_correct(context, progress=self.progress)
        c = report["correction"]
        scaled = ", ".join(f"{n} x{s:.2f}" for n, s in sorted(c["bone_scale"].items()))
        state = "converged" if c["converged"] else "NOT converged (see weak bones)"
        for w in report.get("warnings", []):
            self.report({"WARNING"}, "osteon: " + w)
        return (f"osteon: {state} in {c['rounds']} rounds; scaled {scaled or 'nothing'}; "
                f"max stress {c['max_stress_before_mpa']:.1f} -> {report['max_stress_mpa']:.1f} MPa")
