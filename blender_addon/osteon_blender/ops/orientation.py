"""Find best orientation / Apply orientation (issue 18): the FDM build direction that makes the
model strongest (``osteon.best_orientation`` on the last analysis), previewed as an arrow, and
the turn of the object (and its armature) that puts that direction on the scene's +Z."""

from __future__ import annotations

import bpy
import numpy as np

from .. import bridge, core, printdir, service, state
from ..core import OsteonError
from ._base import OsteonOperator

PREVIEW = "osteon_print_direction"


def run_find(context) -> dict:
    """Best orientation of the active rigged mesh (analysing it first if the last analysis is
    of another object); stored in the scene state and previewed as an arrow empty."""
    osteon = core.import_engine()
    st = state.of(context.scene)
    obj, arm = bridge.find_target(context)
    if context.scene.osteon.print_direction == "BEST" and st.orientation is None:
        st.orientation = {"object": obj.name, "direction": printdir.UP}  # analyse at +Z first
    last = st.last
    if last is None or last["inputs"].obj.name != obj.name:
        service.run_analyze(context)
        last = st.last
    analysis, inp = last["analysis"], last["inputs"]
    try:
        profile = inp.params.get("print_profile")  # "Print settings": re-analysed per candidate
        printed = {} if profile is None else {
            "print_profile": profile, "engine_options": {"junctions": inp.params["junctions"]},
            "model": (inp.vertices_mm, inp.faces, service.engine_skeleton(osteon, inp),
                      inp.weights)}
        res = osteon.best_orientation(analysis, **printed)
    except ValueError as e:
        raise OsteonError(f"osteon could not search orientations of '{obj.name}': {e}") from e
    v = inp.vertices_mm / inp.mm_per_unit
    lo, hi = v.min(axis=0), v.max(axis=0)
    centre = (lo + hi) / 2.0
    st.orientation = {"object": obj.name, "armature": arm.name,
                      "direction": tuple(float(x) for x in res.direction), "result": res,
                      "before": float(res.reference_ratio), "after": float(res.worst_ratio),
                      "centre": centre, "mm_per_unit": inp.mm_per_unit, "applied": False,
                      "matrices": None, "preview": PREVIEW}
    bridge.arrow_empty(context, PREVIEW, centre, res.direction,
                       0.6 * float(np.max(hi - lo)))
    return st.orientation


def reanalyse(context, mm_per_unit: float) -> dict:
    """Analyse again at the given scale (turning the model does not change its printed size)."""
    osteon = core.import_engine()
    inp = service.gather(context, mm_per_unit=mm_per_unit)
    return service.publish(context, inp, service.analyze_inputs(osteon, inp))


def run_apply(context) -> dict:
    """Turn the object (and its armature) about the model's centre so that the found direction
    becomes +Z, then analyse again with print direction +Z at the same mm per unit."""
    st = state.of(context.scene)
    obj, arm = bridge.find_target(context)
    o = st.orientation
    if o is None or "result" not in o or o["object"] != obj.name:
        raise OsteonError(f"No orientation found for '{obj.name}': press 'Find best "
                          "orientation' first")
    if o["applied"]:
        raise OsteonError(f"The orientation of '{obj.name}' is already applied")
    from osteon.orientation import rotation_to_z

    rot = rotation_to_z(np.asarray(o["direction"], float))
    o["matrices"] = bridge.rotate_objects(context, [arm, obj], rot, o["centre"])
    o["applied"] = True
    o["found_direction"] = o["direction"]
    o["direction"] = printdir.UP
    s = context.scene.osteon
    if s.print_direction != "BEST":
        s.print_direction = "Z"
    bridge.remove_object(o.get("preview") or PREVIEW)
    st.weights.clear()
    report = reanalyse(context, o["mm_per_unit"])
    o["reported"] = report["stress_ratio"]
    return report


def revert(context) -> dict:
    """Put the objects back where Apply found them (the stored matrices) and analyse again:
    what Ctrl+Z does in the UI, for scripts and headless runs."""
    st = state.of(context.scene)
    o = st.orientation
    if o is None or not o.get("applied"):
        raise OsteonError("No applied orientation to revert")
    objs = [context.scene.objects[n] for n in o["matrices"] if n in context.scene.objects]
    bridge.set_world_matrices(context, objs, o["matrices"])
    o["applied"] = False
    o["direction"] = o["found_direction"]
    return reanalyse(context, o["mm_per_unit"])


class OSTEON_OT_find_orientation(OsteonOperator, bpy.types.Operator):
    """Search the print (layer) directions for the one with the lowest worst stress ratio
    (FDM layers are weaker across); preview it as an arrow"""

    bl_idname = "osteon.find_orientation"
    bl_label = "Find best orientation"

    def run(self, context):
        o = run_find(context)
        d = o["direction"]
        return (f"osteon: best print direction ({d[0]:.3f}, {d[1]:.3f}, {d[2]:.3f}): worst "
                f"stress ratio {o['before']:.3f} -> {o['after']:.3f}")


class OSTEON_OT_apply_orientation(OsteonOperator, bpy.types.Operator):
    """Turn the object and its armature so the best print direction points up (+Z), then
    analyse again (Ctrl+Z undoes it)"""

    bl_idname = "osteon.apply_orientation"
    bl_label = "Apply orientation"

    def run(self, context):
        o = state.of(context.scene).orientation
        before = o["before"] if o else float("nan")
        report = run_apply(context)
        return (f"osteon: turned so the best print direction is +Z; worst stress ratio "
                f"{before:.3f} -> {report['stress_ratio']:.3f}")


classes = (OSTEON_OT_find_orientation, OSTEON_OT_apply_orientation)
