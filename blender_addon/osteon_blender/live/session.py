"""Live mode's session: what one live session watches and remembers, and the three steps of an
update (read on the main thread -> compute in a worker -> publish on the main thread), plus
:func:`update_now`, the synchronous update.  No timer or handler here (see ``timer``).
Units: mm, N, MPa."""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field

import bpy
import numpy as np

from .. import bridge, core, overlay, results, state
from ..core import OsteonError

# --------------------------------------------------------------------------- session state


@dataclass
class Readout:
    """What the sidebar shows (module state, not scene properties: writing scene
    properties from a timer would itself trigger depsgraph updates)."""

    status: str = "off"            # "off", "live", "paused: ...", "error: ..."
    max_stress_mpa: float = 0.0
    allowable_mpa: float = 0.0
    weakest_bone: str = ""
    weakest_ratio: float = 0.0     # stress / allowable at the governing section (report "worst")
    worst_stress_mpa: float = 0.0
    worst_allowable_mpa: float = 0.0
    worst_limit: str = ""
    sections: int = 0
    weak_sections: int = 0
    updates: int = 0
    last_update_ms: float = 0.0    # read + analysis + colours, wall clock
    analysis_ms: float = 0.0


@dataclass
class LiveInputs:
    """Everything a worker needs (NumPy only, no bpy)."""

    co: np.ndarray                 # (V, 3) float32 object space, evaluated mesh
    matrix: np.ndarray             # (4, 4) mesh world matrix
    heads: np.ndarray              # (B, 3) world (Blender units)
    tails: np.ndarray
    parents: np.ndarray
    names: list
    size_mode: str
    print_size_mm: float
    unit_scale: float
    params: dict                   # force, allowable_stress, interval, root
    analyzer_key: tuple
    faces: np.ndarray | None = None     # only when the analyzer must be rebuilt
    weights: object = None
    want_outlines: bool = False
    t_read: float = 0.0
    skeleton: object = None             # bridge.SkeletonArrays as read (Blender's tails)
    obj_name: str = ""
    arm_name: str = ""
    settings: dict = field(default_factory=dict)   # Settings.as_dict() for the report


@dataclass
class LiveResult:
    analysis: object
    rgba: np.ndarray
    vertices_mm: np.ndarray
    mm_per_unit: float
    names: list
    parents: np.ndarray
    outlines: object = None
    timings: dict = field(default_factory=dict)
    report: dict | None = None          # the wheel's report: the panel shows it (results.show)
    inputs: object = None               # what a row click needs (LiveShown)


@dataclass
class LiveShown:
    """A live result in the shape ops/select_bone reads from ``service.Inputs``."""

    skeleton: object
    mm_per_unit: float
    vertices_mm: np.ndarray


class Session:
    """One live session: a mesh, its armature, the reusable analyzer and what last ran."""

    def __init__(self, scene, obj, arm):
        self.scene_name = scene.name
        self.obj_name = obj.name
        self.arm_name = arm.name
        self.watch = {obj.as_pointer(), arm.as_pointer(), obj.data.as_pointer(),
                      arm.data.as_pointer()}
        self.dirty = True
        self.weights_stale = False
        self.weights = state.of(scene).weights   # the scene's weight cache, shared with Analyze
        self.analyzer = None
        self.analyzer_key = None
        self.faces = None
        self.engine_weights = None      # (V, B) sparse weights the analyzer was built with
        self.last_sig = None            # (co, matrix, heads, tails, settings) last analysed
        self.co_spare = None            # the buffer the next read goes into (not last_sig's)
        self.settings_key = None
        # (settings key, engine params, their key, Settings.as_dict()) of the last read
        self.derived = None
        self.future = None              # running analysis job
        self.outline_future = None      # running outline job
        self.last_result: LiveResult | None = None
        self.outlined = None            # the analysis whose outlines are shown
        self.next_allowed = 0.0         # perf_counter time before which no update starts
        self.started = 0.0              # perf_counter time the running update started
        self.readout = Readout(status="live")


# the session lives in its scene's state (state.SceneState.live); at most one at a time


def session() -> Session | None:
    return state.live_session()


def _set_session(scene_name: str, sess: Session | None) -> None:
    state.of(scene_name).live = sess


def readout(scene) -> Readout:
    st = state.get(scene)
    if st is None:
        return Readout()
    if st.live is not None:
        return st.live.readout
    return st.live_readout if st.live_readout is not None else Readout()


def is_live(scene=None) -> bool:
    sess = state.live_session()
    return sess is not None and (scene is None or sess.scene_name == scene.name)


# --------------------------------------------------------------------------- the three steps


def _settings_key(scene, settings=None) -> tuple:
    """Everything of ``scene.osteon`` that changes the analysis (the wheel's Settings, so a new
    setting is covered without listing it here) and the scene's unit scale; ``settings``: the
    scene's ``core.settings_of`` when the caller has it."""
    s = scene.osteon
    try:
        if settings is None:
            settings = core.settings_of(s, state.of(scene).orientation)
        settings = dataclasses.replace(
            settings, build_direction=tuple(float(x) for x in settings.build_direction))
    except (OsteonError, ValueError, TypeError) as e:  # read_inputs reports it to the user
        settings = str(e)
    return (settings, float(scene.unit_settings.scale_length))


def _params_key(params: dict) -> tuple:
    """The engine arguments as a comparable key (the live Analyzer is built with all of them)."""
    return tuple(sorted((k, tuple(float(x) for x in v) if isinstance(v, (list, tuple, np.ndarray))
                         else v) for k, v in params.items()))


def _objects(sess: Session):
    scene = bpy.data.scenes.get(sess.scene_name)
    obj = scene.objects.get(sess.obj_name) if scene is not None else None
    arm = scene.objects.get(sess.arm_name) if scene is not None else None
    if obj is None or arm is None or obj.type != "MESH" or arm.type != "ARMATURE":
        raise OsteonError(f"Live: '{sess.obj_name}' or its armature '{sess.arm_name}' is gone")
    return scene, obj, arm


class Paused(Exception):
    """Nothing to analyse right now (Edit Mode, another scene shown); not an error."""


def read_inputs(sess: Session, depsgraph=None, force: bool = False) -> LiveInputs | None:
    """Main thread: the posed mesh and skeleton, or None when nothing moved since the
    last analysis.  Raises OsteonError (user problem) or Paused."""
    t0 = time.perf_counter()
    scene, obj, arm = _objects(sess)
    if obj.mode == "EDIT" or arm.mode == "EDIT":
        sess.weights_stale = True       # faces / weights may change there: rebuild after
        raise Paused("Edit Mode")
    if depsgraph is None:
        if bpy.context.scene is None or bpy.context.scene.name != sess.scene_name:
            raise Paused(f"scene '{sess.scene_name}' is not shown")
        depsgraph = bpy.context.evaluated_depsgraph_get()
    s = scene.osteon
    sk = bridge.skeleton_arrays(arm)
    chosen = core.settings_of(s, state.of(scene).orientation)   # once per update
    settings = _settings_key(scene, chosen)
    # the engine arguments, their key and the report's settings change only with the settings
    # (and the bone names): made again only then
    derived_key = (settings, tuple(sk.names))
    if sess.derived is None or sess.derived[0] != derived_key:
        params = core.engine_params(s, arm, sk.names, settings=chosen)
        sess.derived = (derived_key, params, _params_key(params), chosen.as_dict())
    _, params, params_key, settings_dict = sess.derived
    # two buffers in turn: the last analysed read stays in last_sig ("nothing moved" test)
    co, matrix = bridge.evaluated_positions_into(obj, depsgraph, sess.co_spare)
    want = _want_outlines(scene)
    sig = (co, matrix, sk.heads, sk.tails, settings)
    last = sess.last_sig
    key = bridge.topology_key(obj) + (tuple(sk.names), tuple(int(p) for p in sk.parents),
                                       params_key)
    rebuild = sess.analyzer is None or key != sess.analyzer_key or sess.weights_stale
    if (not force and not rebuild and last is not None and last[4] == settings
            and np.array_equal(last[0], co) and np.array_equal(last[1], matrix)
            and np.array_equal(last[2], sk.heads) and np.array_equal(last[3], sk.tails)):
        sess.co_spare = co
        return None
    sess.co_spare = last[0] if last is not None else None
    sess.last_sig = sig
    inp = LiveInputs(
        co=co, matrix=matrix, heads=sk.heads, tails=sk.tails, parents=sk.parents,
        names=list(sk.names), size_mode=s.size_mode, print_size_mm=float(s.print_size_mm),
        unit_scale=float(scene.unit_settings.scale_length),
        params=params,
        analyzer_key=key, want_outlines=want, skeleton=sk, obj_name=obj.name,
        arm_name=arm.name,
        settings=settings_dict)
    if rebuild:
        if sess.weights_stale:
            sess.weights.clear()
            sess.weights_stale = False
        inp.faces = bridge.triangles(obj.data)
        if len(inp.faces) == 0:
            raise OsteonError(f"Mesh '{obj.name}' has no faces")
        inp.weights = bridge.sparse_weights(sess.weights.get(obj, sk.names), len(sk.names))
    inp.t_read = time.perf_counter() - t0
    return inp


def compute(sess: Session, inp: LiveInputs) -> LiveResult:
    """Worker-safe (NumPy + engine only): world mm positions, analysis, colours."""
    osteon = core.import_engine()
    t0 = time.perf_counter()
    m = inp.matrix
    w = inp.co                                      # float32, object space (Blender's own)
    if not np.array_equal(m, np.eye(4)):            # rigged meshes mostly sit at identity
        w = w @ m[:3, :3].T.astype(np.float32)
        w += m[:3, 3].astype(np.float32)
    # per column: a strided axis-0 reduction over (V, 3) is ~20x slower in NumPy; only the
    # columns the print-size mode reads (HEIGHT: z; UNITS: none)
    extent = np.zeros(3)
    for i in {"HEIGHT": (2,), "UNITS": ()}.get(inp.size_mode, (0, 1, 2)):
        extent[i] = float(w[:, i].max()) - float(w[:, i].min())
    try:
        k = core.mm_per_unit(inp.size_mode, inp.print_size_mm, extent, inp.unit_scale)
    except ValueError as e:
        raise OsteonError(str(e)) from e
    world = np.multiply(w, k, dtype=np.float64)    # world mm, one pass
    if inp.faces is not None:
        sess.faces = inp.faces
        sess.engine_weights = inp.weights
        sess.analyzer = None
    tails = inp.tails
    if inp.skeleton is not None:
        # joint rigs (FBX/glTF imports): the same joint-segment step as Analyze (service.gather)
        tails = bridge.use_joint_segments(inp.skeleton, w, sess.engine_weights).tails
    try:
        skeleton = osteon.Skeleton(inp.heads * k, tails * k, inp.parents, names=inp.names)
        if sess.analyzer is None:
            sess.analyzer = osteon.Analyzer(sess.faces, len(world), skeleton, inp.weights,
                                            keep_outlines=True, **inp.params)
            sess.analyzer_key = inp.analyzer_key
        t1 = time.perf_counter()
        analysis = sess.analyzer.run(world, skeleton)
    except ValueError as e:
        sess.analyzer = None
        sess.analyzer_key = None
        raise OsteonError(f"osteon could not analyse '{sess.obj_name}': {e}") from e
    t2 = time.perf_counter()
    # the same report and colours as Analyze (service.publish): one verdict everywhere; the
    # per-section rows (which the panel does not show) once the pose is still (complete_report)
    report = core.build_report(
        object_name=inp.obj_name, armature_name=inp.arm_name, bone_names=inp.names,
        analysis=analysis, allowable_mpa=inp.params["allowable_stress"], settings=inp.settings,
        mm_per_unit=k, vertices=len(world), faces=len(sess.faces), section_table=False)
    doubt = results.not_analysed_vertices(analysis, report, inp.names)
    rgba = core.result_colors(analysis, inp.heads * k, tails * k, doubt)
    t3 = time.perf_counter()
    shown = LiveShown(skeleton=inp.skeleton, mm_per_unit=k, vertices_mm=world)
    return LiveResult(analysis=analysis, rgba=rgba, vertices_mm=world, mm_per_unit=k,
                      names=inp.names, parents=inp.parents, report=report, inputs=shown,
                      timings={"read_ms": inp.t_read * 1e3, "prepare_ms": (t1 - t0) * 1e3,
                               "analysis_ms": (t2 - t1) * 1e3, "colors_ms": (t3 - t2) * 1e3})



def complete_report(sess: Session) -> None:
    """The pose is still (or Live stops): the last result's report gets its per-section rows,
    so that the report the panel keeps is whole (compute leaves them out per update)."""
    res = sess.last_result
    if res is not None and res.report is not None and res.report.get("section_table") is None:
        res.report["section_table"] = core.report.section_rows(res.analysis, res.names)


def outlines_of(sess: Session, res: LiveResult):
    """Worker-safe: the overlay outlines of a live result."""
    return overlay.compute_outlines(res.analysis, res.mm_per_unit)


def publish(sess: Session, res: LiveResult) -> None:
    """Main thread: colours into ``osteon_stress`` (bridge), readout, overlay."""
    t0 = time.perf_counter()
    scene, obj, _arm = _objects(sess)
    if len(obj.data.vertices) != len(res.rgba):
        raise OsteonError(f"Mesh '{obj.name}' changed its vertex count during the update")
    bridge.write_point_colors(obj.data, res.rgba)
    a = res.analysis
    allowable = float(a.allowable_stress)
    r = sess.readout
    r.status = "live"
    r.max_stress_mpa = float(np.nan_to_num(a.max_stress))
    r.allowable_mpa = allowable
    worst = (res.report or {}).get("worst")     # the governing section, as Analyze reports it
    if worst:
        r.weakest_bone, r.weakest_ratio = worst["bone"], float(worst["ratio"])
        r.worst_stress_mpa, r.worst_allowable_mpa = (float(worst["stress_mpa"]),
                                                     float(worst["allowable_mpa"]))
        r.worst_limit = worst.get("limit") or ""
    else:
        r.weakest_bone, r.weakest_ratio = "", 0.0
        r.worst_stress_mpa = r.worst_allowable_mpa = 0.0
        r.worst_limit = ""
    r.sections = int(a.num_sections)
    r.weak_sections = int(np.count_nonzero(a.weak))
    if res.report is not None:
        # Live's result IS the panel's: the summary and the rows show it too
        results.show(scene, res.report, {"report": res.report, "analysis": a,
                                         "inputs": res.inputs, "correction": None}, "live")
    r.updates += 1
    r.analysis_ms = res.timings.get("analysis_ms", 0.0)
    res.timings["write_ms"] = (time.perf_counter() - t0) * 1e3
    r.last_update_ms = sum(res.timings.get(k, 0.0) for k in
                           ("read_ms", "prepare_ms", "analysis_ms", "colors_ms", "write_ms"))
    sess.last_result = res
    if res.outlines is not None:
        overlay.set_outlines(scene.name, a, res.outlines)
        sess.outlined = a
    bridge.tag_redraw_view3d(("UI",))


def _want_outlines(scene) -> bool:
    s = getattr(scene, "osteon_live", None)
    return bool(s is not None and s.show_sections)


def update_now(force: bool = False, depsgraph=None, outlines: bool | None = None) -> Readout:
    """Synchronous live update (read -> analyse -> colours [-> outlines]) of the running
    session; returns the readout.  Raises OsteonError when there is no session or the
    update failed (the readout then says why)."""
    sess = state.live_session()
    if sess is None:
        raise OsteonError("Live is off")
    _wait_jobs(sess)
    try:
        inp = read_inputs(sess, depsgraph=depsgraph, force=force)
    except Paused as e:
        sess.readout.status = f"paused: {e}"
        return sess.readout
    except OsteonError as e:
        sess.readout.status = f"error: {e}"
        raise
    sess.dirty = False
    if inp is None:
        complete_report(sess)
        return sess.readout
    try:
        res = compute(sess, inp)
        scene = bpy.data.scenes[sess.scene_name]
        if outlines if outlines is not None else _want_outlines(scene):
            res.outlines = outlines_of(sess, res)
        publish(sess, res)
    except OsteonError as e:
        sess.readout.status = f"error: {e}"
        raise
    return sess.readout


def _wait_jobs(sess: Session) -> None:
    for name in ("future", "outline_future"):
        fut = getattr(sess, name)
        if fut is not None:
            try:
                fut.result()
            except Exception as e:  # noqa: BLE001 -- a dropped background job
                print(f"osteon live: dropped update ({type(e).__name__}: {e})")
            setattr(sess, name, None)
