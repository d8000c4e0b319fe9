import bpy

from .. import service
from ._base import OsteonJobOperator


class OSTEON_OT_correct(OsteonJobOperator, bpy.types.Operator):
    """Thicken weak bones: scale pose bones across their axis (length kept, children keep
    shape and place) until no section exceeds the allowable stress (MPa); Reset undoes it.
    Shows its progress in the status bar; Esc cancels (the pose is left as it was)"""

    bl_idname = "osteon.correct"
    bl_label = "Correct"

    def steps(self, job):
        return service.correct_steps(job)

    def finished(self, report: dict) -> str:
        c = report["correction"]
        scaled = ", ".join(f"{n} x{s:.2f}" for n, s in sorted(c["bone_scale"].items()))
        state = "converged" if c["converged"] else "NOT converged (see weak bones)"
        for w in report.get("warnings", []):
            self.report({"WARNING"}, "osteon: " + w)
        return (f"osteon: {state} in {c['rounds']} rounds; scaled {scaled or 'nothing'}; "
                f"max stress {c['max_stress_before_mpa']:.1f} -> {report['max_stress_mpa']:.1f} MPa")
