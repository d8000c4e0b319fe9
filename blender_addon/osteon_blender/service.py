"""The add-on's service module: the steps behind the operators and the batch script.
Gather the inputs from Blender (through the bridge), call the engine, publish the
results (stress layer, sidebar list, the scene's state in ``state``).

Nothing here writes to Blender until the engine has answered, so a failing
operator leaves the scene as it was."""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field

import numpy as np

from . import bridge, core, results, state
from .core import OsteonError, min_thickness_mm

# read-only view: scene name -> the last result (report, Analysis, inputs, correction),
# kept in the scene's state object
LAST = state.LAST


@dataclass
class Inputs:
    obj: object
    arm: object
    skeleton: bridge.SkeletonArrays
    vertices_mm: np.ndarray
    faces: np.ndarray
    csr: tuple
    weights: object
    mm_per_unit: float
    root: int | None
    params: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)


def gather(context, use_weight_cache: bool = False, mm_per_unit: float | None = None) -> Inputs:
    """Read the active rigged mesh (posed, evaluated, world space) in mm.  ``mm_per_unit``
    fixes the scale (after a correction, so that the thicker model keeps its scale)."""
    s = context.scene.osteon
    t0 = time.perf_counter()
    obj, arm = bridge.find_target(context)
    sk = bridge.skeleton_arrays(arm)
    params = core.engine_params(s, arm, sk.names,
                                orientation=state.of(context.scene).orientation)
    csr = (state.of(context.scene).weights.get(obj, sk.names) if use_weight_cache
           else bridge.vertex_weights_csr(obj, sk.names))
    t1 = time.perf_counter()
    depsgraph = context.evaluated_depsgraph_get()
    verts = bridge.evaluated_positions(obj, depsgraph)
    faces = bridge.triangles(obj.data)
    if len(faces) == 0:
        raise OsteonError(f"Mesh '{obj.name}' has no faces")
    extent = verts.max(axis=0) - verts.min(axis=0)
    try:
        k = mm_per_unit if mm_per_unit is not None else core.mm_per_unit(s.size_mode, s.print_size_mm, extent,
                             context.scene.unit_settings.scale_length)
    except ValueError as e:
        raise OsteonError(str(e)) from e
    weights = bridge.sparse_weights(csr, len(sk.names))
    # joint rigs (FBX/glTF imports): the segments the joints mean, not Blender's tails
    bridge.use_joint_segments(sk, verts, weights)
    t2 = time.perf_counter()
    return Inputs(
        obj=obj, arm=arm, skeleton=sk, vertices_mm=verts * k, faces=faces, csr=csr,
        weights=weights, mm_per_unit=k, root=params["root"],
        params=params,
        timings={"read_weights_s": t1 - t0, "read_mesh_s": t2 - t1},
    )


def engine_skeleton(osteon, inp: Inputs):
    sk = inp.skeleton
    try:
        return osteon.Skeleton(sk.heads * inp.mm_per_unit, sk.tails * inp.mm_per_unit,
                               sk.parents, names=list(sk.names))
    except ValueError as e:
        raise OsteonError(f"osteon rejected the skeleton of '{inp.arm.name}': {e}") from e


def analyze_inputs(osteon, inp: Inputs, skeleton=None, progress=None):
    """The engine's analysis of ``inp`` (safe to call from a worker thread: no bpy);
    ``progress``: an ``osteon.Progress`` to follow or cancel it."""
    skeleton = skeleton if skeleton is not None else engine_skeleton(osteon, inp)
    try:
        return osteon.analyze(inp.vertices_mm, inp.faces, skeleton, inp.weights,
                              keep_outlines=True, progress=progress, **inp.params)
    except ValueError as e:
        raise OsteonError(f"osteon could not analyse '{inp.obj.name}': {e}") from e


# --------------------------------------------------------------------------- jobs
#
# Analyze and Correct are written once, as generators of steps: the Blender part (read the
# scene, write the results) runs in the generator on the main thread; each engine call is
# yielded as a function of no arguments. run_steps() calls those at once (scripts, background
# mode, batch); the interactive operators call them in a worker thread (the engine releases the
# GIL) and resume the generator from a modal timer, so that Blender keeps drawing, shows the
# progress and cancels on Esc. On a cancel or an error the runner throws the exception into the
# generator, whose cleanup leaves the scene as it was.


class Job:
    """One run of a job: the current ``context`` (the runner sets it before every resume:
    a context must not be kept across events), the engine's ``progress`` (an
    ``osteon.Progress`` or None), ``max_sections`` (the guard's limit, 0 = none) and ``stage``
    (what the engine is doing, for the status bar)."""

    def __init__(self, context, progress=None, max_sections: int = 0,
                 use_weight_cache: bool = False):
        self.context = context
        self.progress = progress
        self.max_sections = int(max_sections)
        self.use_weight_cache = use_weight_cache
        self.stage = ""


class TooManySections(OsteonError):
    """The setting would make more sections than the guard allows (the message says how many
    and why); raised before any work is done."""


def check_sections(osteon, inp: Inputs, skeleton, max_sections: int) -> int:
    """The number of sections the analysis of ``inp`` would make (``osteon.estimate_sections``,
    exact, no cut); :class:`TooManySections` above ``max_sections`` (> 0)."""
    from osteon.settings import section_guard

    n = osteon.estimate_sections(skeleton, inp.params["interval"])
    if max_sections > 0:
        size = float(np.max(inp.vertices_mm.max(axis=0) - inp.vertices_mm.min(axis=0)))
        msg = section_guard(n, inp.params["interval"], size, max_sections)
        if msg:
            raise TooManySections(msg)
    return n


def run_steps(steps):
    """Runs a job's steps at once, in this thread; returns the job's result."""
    try:
        work = next(steps)
        while True:
            try:
                value = work()
            except BaseException as e:  # noqa: BLE001 -- handed to the job's cleanup
                work = steps.throw(e)
                continue
            work = steps.send(value)
    except StopIteration as stop:
        return stop.value


def analyze_steps(job: Job):
    """Analyze as steps (see :class:`Job`): returns the report."""
    osteon = core.import_engine()
    inp = gather(job.context, job.use_weight_cache)
    skeleton = engine_skeleton(osteon, inp)
    check_sections(osteon, inp, skeleton, job.max_sections)
    job.stage = "Analyze"
    analysis = yield lambda: analyze_inputs(osteon, inp, skeleton, progress=job.progress)
    return publish(job.context, inp, analysis)


def publish(context, inp: Inputs, analysis, correction=None, first_analysis=None) -> dict:
    """Write the stress layer and the results list; remember the report."""
    s = context.scene.osteon
    allowable = inp.params["allowable_stress"]
    report = core.build_report(
        object_name=inp.obj.name, armature_name=inp.arm.name, bone_names=inp.skeleton.names,
        analysis=first_analysis if first_analysis is not None else analysis,
        corrected_analysis=analysis if correction is not None else None,
        allowable_mpa=allowable, settings=core.settings_of(
            s, state.of(context.scene).orientation).as_dict(), mm_per_unit=inp.mm_per_unit,
        correction=correction, vertices=len(inp.vertices_mm), faces=len(inp.faces))
    k = inp.mm_per_unit
    rgba = core.result_colors(analysis, inp.skeleton.heads * k, inp.skeleton.tails * k,
                              results.not_analysed_vertices(analysis, report, inp.skeleton.names))
    bridge.write_point_colors(inp.obj.data, rgba)
    bridge.show_colors_in_viewports()
    entry = {"report": report, "analysis": analysis, "inputs": inp, "correction": correction}
    results.show(context.scene, report, entry, "correct" if correction is not None else "analyze")
    s.weak_bones_index = -1
    st = state.of(context.scene)
    st.last = entry
    st.loose_pieces = {"object": inp.obj.name, "vertices": len(inp.vertices_mm),
                       "pieces": [np.asarray(p, dtype=np.int64)
                                  for p in getattr(analysis, "loose_pieces", [])]}
    return report


def clear_results(context):
    s = context.scene.osteon
    s.weak_bones.clear()
    s.weak_bones_index = -1
    s.has_result = False
    s.max_stress_mpa = 0.0
    s.sections = 0
    s.skipped_sections = 0
    s.doubt = ""
    s.verdict = ""
    s.weak_sections = 0
    s.worst_bone = s.worst_limit = s.result_source = ""
    s.worst_stress_mpa = s.worst_allowable_mpa = s.worst_ratio = 0.0
    st = state.get(context.scene)
    if st is not None:
        st.last = st.shown = None
        st.loose_pieces = None


def summary(report: dict) -> str:
    weak = [r["bone"] for r in report["weak_bones"] if r.get("weak", True)]
    n = len(weak)
    worst = results.report_worst_line(report)
    msg = (f"osteon: {worst or 'no stress'}, {report['sections']} sections, "
           f"{n} weak bone{'s' if n != 1 else ''}")
    if n:
        msg += " (" + ", ".join(weak[:5]) + ")"
    if report.get("doubt"):
        msg += "; NOT A CLEAN RESULT: " + report["doubt"]
    loose = core.loose_pieces_sentence(report.get("loose_pieces") or [])
    if loose:
        msg += "; " + loose + " (Select Loose Pieces shows them)"
    return msg


def _no_progress(_fraction: float) -> None:
    pass


def run_analyze(context, use_weight_cache: bool = False, progress=_no_progress,
                max_sections: int = 0) -> dict:
    """Analyze at once (scripts, background mode); ``max_sections`` > 0: refuse above it."""
    progress(0.4)
    report = run_steps(analyze_steps(Job(context, max_sections=max_sections,
                                         use_weight_cache=use_weight_cache)))
    progress(0.9)
    return report


def correct_steps(job: Job):
    """Correct as steps (see :class:`Job`): engine correction -> pose-bone scales ->
    re-analysis of Blender's own result; returns the report. On any error or a cancel the pose
    is put back as it was."""
    osteon = core.import_engine()
    context = job.context
    s = context.scene.osteon
    # analyse from the user's own pose: undo a previous correction first (restored on error)
    obj, arm = bridge.find_target(context)
    had_previous = bridge.has_saved_pose(arm)
    prev_ratios = bridge.correction_ratios(arm)
    bridge.restore_pose(context, arm)
    try:
        inp = gather(context)
        skeleton = engine_skeleton(osteon, inp)
        check_sections(osteon, inp, skeleton, job.max_sections)
        params = core.engine_params(s, arm, inp.skeleton.names, correct=True,
                                    orientation=state.of(context.scene).orientation)

        def engine_correct():
            try:
                # The bones' own X axes: a thin-direction scale must be one Blender's pose
                # scale X or Z can reproduce; on a joint rig, also the local axis each bone
                # scales across (its segment is not its Y axis).
                first = reinforce_first_params(s, params)
                return osteon.correct(inp.vertices_mm, inp.faces, skeleton, inp.weights,
                                      bone_x_axes=inp.skeleton.x_axes,
                                      bone_long_axes=inp.skeleton.long_axes, keep_outlines=True,
                                      progress=job.progress, **params, **first)
            except ValueError as e:
                raise OsteonError(f"osteon could not correct '{inp.obj.name}': {e}") from e

        job.stage = "Correct"
        fix = yield engine_correct
        context = job.context
        scales = bridge.correction_pose_scales(inp.skeleton, fix.bone_scale_x,
                                               fix.bone_scale_z)
        bridge.apply_bone_scales(context, arm, scales)
        after_inp = gather(context, mm_per_unit=inp.mm_per_unit)
        job.stage = "Correct: analysing the result"
        after = yield lambda: analyze_inputs(osteon, after_inp, progress=job.progress)
        context = job.context
        if fix.reinforcement is not None:
            # printed with the regions' walls and infill: the engine's reinforced analysis
            # (Blender's re-analysis knows only the profile); the modifiers shown
            after = fix.after
            bridge.show_modifiers(context, fix.reinforcement, inp.mm_per_unit)
    except Exception:  # leave the pose as it was before this call (errors, cancel)
        bridge.restore_pose(job.context, arm)
        if had_previous:
            bridge.apply_bone_scales(job.context, arm, prev_ratios)
        raise
    report = publish(context, after_inp, after, correction=fix, first_analysis=fix.before)
    report["warnings"] = correction_warnings(context, obj, arm)
    if fix.reinforcement is not None:
        from osteon.report import reinforcement_section

        report["reinforcement"] = reinforcement_section(fix.reinforcement)
    return report


def reinforce_first_params(s, params: dict) -> dict:
    """``reinforce_first=True`` for ``osteon.correct`` when "Reinforce first (keep shape)" is
    on (the print profile must be an FDM one: walls and infill to change)."""
    if not getattr(s, "reinforce_first", False):
        return {}
    profile = params.get("print_profile")
    if profile is None or getattr(profile, "kind", None) != "fdm":
        raise OsteonError("Reinforce first needs an FDM print profile (walls and infill): "
                          "choose one under Print settings")
    return {"reinforce_first": True}


def run_correct(context, progress=_no_progress, max_sections: int = 0) -> dict:
    """Correct at once (scripts, background mode); ``max_sections`` > 0: refuse above it."""
    progress(0.2)
    report = run_steps(correct_steps(Job(context, max_sections=max_sections)))
    progress(0.9)
    return report


def correction_warnings(context, obj, arm) -> list[str]:
    """Cases where Blender's deformation of the pose scales differs from the engine's."""
    out = []
    for mod in obj.modifiers:
        if mod.type == "ARMATURE" and mod.object is arm:
            if mod.use_deform_preserve_volume:
                out.append(f"'{obj.name}': the Armature modifier uses Preserve Volume (dual "
                           "quaternions); the engine assumed linear blend skinning")
            if not mod.use_vertex_groups:
                out.append(f"'{obj.name}': the Armature modifier does not use vertex groups")
            break
    others = [o.name for o in bridge.meshes_of_armature(arm, context.scene) if o is not obj]
    if others:
        out.append(f"the pose scales also thicken {', '.join(sorted(others))}")
    return out


def run_reset(context) -> bool:
    obj, arm = bridge.find_target(context)
    restored = bridge.restore_pose(context, arm)
    removed = bridge.remove_point_colors(obj.data)
    clear_results(context)
    return restored or removed


def run_apply(context) -> dict:
    """Bake the correction's pose scales into the mesh (the only step that edits the
    mesh), restore the pose, and analyse the result."""
    obj, arm = bridge.find_target(context)
    ratios = bridge.correction_ratios(arm)
    if not ratios:
        raise OsteonError(f"Nothing to apply: armature '{arm.name}' carries no osteon correction "
                          "(run Correct first)")
    if obj.data.shape_keys is not None:
        raise OsteonError(f"Mesh '{obj.name}' has shape keys: Apply would not update them; "
                          "apply or remove the shape keys first")
    if obj.data.users > 1:
        raise OsteonError(f"Mesh data '{obj.data.name}' is shared by {obj.data.users} users; "
                          "make it single-user first")
    sk = bridge.skeleton_arrays(arm)
    csr = bridge.vertex_weights_csr(obj, sk.names)
    co = bridge.bake_scales_into_mesh(obj, arm, ratios, sk.names, csr)
    bridge.set_local_positions(obj.data, co)
    bridge.restore_pose(context, arm)
    state.of(context.scene).weights.clear()
    return run_analyze(context)


#: Make skeleton writes weights in steps of 1 / WEIGHT_LEVELS, as glTF 2.0 skins may store them
#: (WEIGHTS_n as normalised unsigned bytes): bpy sets one weight per ``VertexGroup.add`` call, and
#: 1/256 steps need a third of the calls of 1/1024 (cow x4, 41 bones: 7 800 calls, 0.08 s CPU in
#: Blender 3.4.1, instead of 26 500 calls, 0.23 s; issue 35: Make skeleton within 2 s)
WEIGHT_LEVELS = 256


def byte_weights(w):
    """The (V, B) SciPy CSR weights ``w`` (rows summing to 1) rounded to multiples of
    1 / ``WEIGHT_LEVELS`` that still sum to exactly 1 per row (largest remainders round up)."""
    w = w.tocsr()
    scaled = np.asarray(w.data, float) * WEIGHT_LEVELS
    q = np.floor(scaled)
    row = np.repeat(np.arange(w.shape[0]), np.diff(w.indptr))
    short = np.rint(WEIGHT_LEVELS * np.bincount(row, w.data, minlength=w.shape[0])
                    - np.bincount(row, q, minlength=w.shape[0])).astype(np.int64)
    order = np.lexsort((-(scaled - q), row))  # by row, then largest remainder first
    rank = np.arange(len(order)) - w.indptr[row[order]]
    q[order[rank < short[row[order]]]] += 1.0
    out = w.copy()
    out.data = q / WEIGHT_LEVELS
    return out


def run_make_skeleton(context, auto_weights: bool = False, root: str = "centre",
                      progress=_no_progress) -> dict:
    """Rig the active unrigged mesh: an Armature object from :func:`osteon.auto_skeleton`
    (computed in mm at the print size, built in Blender units), vertex groups with the engine's
    weights (or Blender's automatic weights) and an Armature modifier.  The mesh's vertices are
    not changed.  Returns {"armature", "bones", "seconds", "weights", "warnings": the texts
    of the wheel's :class:`osteon.autoskeleton.LoosePiecesWarning` (pieces touching nothing,
    bound whole to their nearest bone), for a WARNING report}."""
    osteon = core.import_engine()
    obj = context.active_object
    if obj is None or obj.type != "MESH":
        raise OsteonError("Make skeleton: select the mesh to rig (the active object is not a mesh)")
    if bridge.armature_of(obj) is not None:
        raise OsteonError(f"Mesh '{obj.name}' already has an Armature modifier")
    core.import_pygel3d()  # auto_skeleton imports it lazily: check first, say what to do
    s = context.scene.osteon
    verts = bridge.world_rest_positions(obj)
    faces = bridge.triangles(obj.data)
    if len(faces) == 0:
        raise OsteonError(f"Mesh '{obj.name}' has no faces")
    try:
        k = core.mm_per_unit(s.size_mode, s.print_size_mm, verts.max(0) - verts.min(0),
                             context.scene.unit_settings.scale_length)
    except ValueError as e:
        raise OsteonError(str(e)) from e
    progress(0.1)
    t0 = time.perf_counter()
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", osteon.autoskeleton.LoosePiecesWarning)
            sk, w = osteon.auto_skeleton(verts * k, faces, root=root,
                                         min_thickness=min_thickness_mm(
                                             core.settings_of(s, state.of(context.scene).orientation)))
    except ValueError as e:
        raise OsteonError(f"Make skeleton: {e}") from e
    # the wheel's own words, once: the operator reports them as a WARNING, batch prints them
    loose = [f"Mesh '{obj.name}': {c.message} -- after Analyze, Select Loose Pieces selects them"
             for c in caught if issubclass(c.category, osteon.autoskeleton.LoosePiecesWarning)]
    for c in caught:  # any other warning goes where it would have gone
        if not issubclass(c.category, osteon.autoskeleton.LoosePiecesWarning):
            warnings.showwarning(c.message, c.category, c.filename, c.lineno)
    progress(0.7)
    names = list(sk.names)
    arm = bridge.build_armature(context, f"{obj.name}_skeleton", np.asarray(sk.heads) / k,
                                np.asarray(sk.tails) / k, np.asarray(sk.parents), names)
    if not auto_weights:
        bridge.write_bone_weights(obj, names, byte_weights(w), step=1.0 / WEIGHT_LEVELS)
    bridge.bind_armature(context, obj, arm, auto_weights=auto_weights)
    context.view_layer.objects.active = obj
    obj.select_set(True)
    state.of(context.scene).weights.clear()
    return {"armature": arm.name, "bones": len(names), "seconds": time.perf_counter() - t0,
            "weights": "Blender automatic" if auto_weights else "osteon", "warnings": loose}
