"""Live mode: re-analyse the rigged mesh while the user poses or edits it.

Pieces, and who runs them:

* ``_on_depsgraph`` (``depsgraph_update_post``) and ``_on_frame`` (``frame_change_post``):
  only note that the watched mesh / armature (or the osteon settings) changed -- a few
  pointer comparisons, no data reads.
* ``_tick`` (a ``bpy.app.timers`` timer): at most every ``throttle_ms`` (and never more
  than half the time: the gap after an update is at least as long as the update took)
  reads the posed mesh and skeleton through the bridge (main thread, ~ one
  ``foreach_get``), skips the work when nothing actually moved, and hands the numbers to
  ONE worker thread: the engine releases the GIL, so Blender's UI keeps running while
  the analysis runs.  The next tick writes the ``osteon_stress`` colours (bridge) and the
  sidebar readout.  Outlines for the overlay are computed in a second, lower-priority
  worker job once the pose has stopped changing.
* One ``osteon.Analyzer`` per session, rebuilt only when the topology, the weights or
  the analysis settings change.
* :func:`update_now` runs the same three steps synchronously: background mode, tests,
  benchmark, and the first run when Live is switched on.

Handlers are added when Live is switched on and removed when it is switched off, on
unregister and when a file is loaded.  ``persistent`` is used twice, on purpose: the
``load_post`` handler (registered with the add-on) is what ends a session when another
file replaces the scene, and the timer is registered persistent so that it is that
handler, not Blender, which removes it (a timer dropped by a file load makes the bpy 4.5
wheel hang at exit).
"""

from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import bpy
import numpy as np
from bpy.app.handlers import persistent
from bpy.props import BoolProperty, IntProperty

from . import bridge, core, overlay
from .core import OsteonError

# --------------------------------------------------------------------------- session state


@dataclass
class Readout:
    """What the sidebar shows (module state, not scene properties: writing scene
    properties from a timer would itself trigger depsgraph updates)."""

    status: str = "off"            # "off", "live", "paused: ...", "error: ..."
    max_stress_mpa: float = 0.0
    allowable_mpa: float = 0.0
    weakest_bone: str = ""
    weakest_ratio: float = 0.0
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
        self.weights = bridge.WeightCache()
        self.analyzer = None
        self.analyzer_key = None
        self.faces = None
        self.domains = overlay.DomainCache()
        self.last_sig = None            # (co, matrix, heads, tails, settings) last analysed
        self.settings_key = None
        self.future = None              # running analysis job
        self.outline_future = None      # running outline job
        self.last_result: LiveResult | None = None
        self.outlined = None            # the analysis whose outlines are shown
        self.next_allowed = 0.0         # perf_counter time before which no update starts
        self.started = 0.0              # perf_counter time the running update started
        self.readout = Readout(status="live")


_session: Session | None = None
_executor: ThreadPoolExecutor | None = None
_last_readout: dict[str, Readout] = {}


def session() -> Session | None:
    return _session


def readout(scene) -> Readout:
    if _session is not None and _session.scene_name == scene.name:
        return _session.readout
    return _last_readout.get(scene.name, Readout())


def is_live(scene=None) -> bool:
    return _session is not None and (scene is None or _session.scene_name == scene.name)


def _pool() -> ThreadPoolExecutor:
    global _executor
    if _executor is None:
        _executor = ThreadPoolExecutor(max_workers=1, thread_name_prefix="osteon-live")
    return _executor


# --------------------------------------------------------------------------- the three steps


def _settings_key(scene) -> tuple:
    s = scene.osteon
    return (float(s.strength_mpa), float(s.safety_factor), float(s.force_n), s.size_mode,
            float(s.print_size_mm), float(s.interval_mm), s.held_bone,
            float(scene.unit_settings.scale_length))


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
    params = core.engine_params(s, arm, sk.names)
    allowable, root = params["allowable_stress"], params["root"]
    co, matrix = bridge.evaluated_positions_into(obj, depsgraph)
    settings = _settings_key(scene)
    want = _want_outlines(scene)
    sig = (co, matrix, sk.heads, sk.tails, settings)
    last = sess.last_sig
    key = bridge.topology_key(obj) + (tuple(sk.names), tuple(int(p) for p in sk.parents),
                                       float(s.force_n), allowable, float(s.interval_mm), root)
    rebuild = sess.analyzer is None or key != sess.analyzer_key or sess.weights_stale
    if (not force and not rebuild and last is not None and last[4] == settings
            and np.array_equal(last[0], co) and np.array_equal(last[1], matrix)
            and np.array_equal(last[2], sk.heads) and np.array_equal(last[3], sk.tails)):
        return None
    sess.last_sig = sig
    inp = LiveInputs(
        co=co, matrix=matrix, heads=sk.heads, tails=sk.tails, parents=sk.parents,
        names=list(sk.names), size_mode=s.size_mode, print_size_mm=float(s.print_size_mm),
        unit_scale=float(scene.unit_settings.scale_length),
        params=params,
        analyzer_key=key, want_outlines=want)
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
    # per column: a strided axis-0 reduction over (V, 3) is ~20x slower in NumPy
    extent = np.array([float(c.max()) - float(c.min()) for c in w.T])
    try:
        k = core.mm_per_unit(inp.size_mode, inp.print_size_mm, extent, inp.unit_scale)
    except ValueError as e:
        raise OsteonError(str(e)) from e
    world = np.multiply(w, k, dtype=np.float64)    # world mm, one pass
    if inp.faces is not None:
        sess.faces = inp.faces
        sess.analyzer = None
    try:
        skeleton = osteon.Skeleton(inp.heads * k, inp.tails * k, inp.parents, names=inp.names)
        if sess.analyzer is None:
            sess.analyzer = osteon.Analyzer(sess.faces, len(world), skeleton, inp.weights,
                                            **inp.params)
            sess.analyzer_key = inp.analyzer_key
        t1 = time.perf_counter()
        analysis = sess.analyzer.run(world, skeleton)
    except ValueError as e:
        sess.analyzer = None
        sess.analyzer_key = None
        raise OsteonError(f"osteon could not analyse '{sess.obj_name}': {e}") from e
    t2 = time.perf_counter()
    rgba = core.stress_colors(analysis.vertex_stress, inp.params["allowable_stress"],
                              analysis.vertex_culled)
    t3 = time.perf_counter()
    return LiveResult(analysis=analysis, rgba=rgba, vertices_mm=world, mm_per_unit=k,
                      names=inp.names, parents=inp.parents,
                      timings={"read_ms": inp.t_read * 1e3, "prepare_ms": (t1 - t0) * 1e3,
                               "analysis_ms": (t2 - t1) * 1e3, "colors_ms": (t3 - t2) * 1e3})


def outlines_of(sess: Session, res: LiveResult):
    """Worker-safe: the overlay outlines of a live result."""
    return overlay.compute_outlines(res.analysis, res.vertices_mm, sess.faces, res.parents,
                                    res.mm_per_unit, domains=sess.domains)


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
    per_bone = a.bone_max_stress()
    if len(per_bone) and np.any(per_bone > 0):
        b = int(np.argmax(per_bone))
        r.weakest_bone, r.weakest_ratio = res.names[b], float(per_bone[b] / allowable)
    else:
        r.weakest_bone, r.weakest_ratio = "", 0.0
    r.sections = int(a.num_sections)
    r.weak_sections = int(np.count_nonzero(a.weak))
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
    sess = _session
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


# --------------------------------------------------------------------------- timer


def _throttle_s(sess: Session) -> float:
    scene = bpy.data.scenes.get(sess.scene_name)
    s = getattr(scene, "osteon_live", None) if scene is not None else None
    return max(0.0, (s.throttle_ms if s is not None else 50) / 1000.0)


_POLL_S = 0.01


def _tick():
    """bpy.app.timers callback; returns the seconds until the next call (None = stop)."""
    sess = _session
    if sess is None:
        return None
    now = time.perf_counter()
    try:
        # 1. a finished analysis: publish it
        if sess.future is not None:
            if not sess.future.done():
                return _POLL_S
            fut, sess.future = sess.future, None
            res = fut.result()                      # OsteonError -> readout below
            publish(sess, res)
            spent = time.perf_counter() - sess.started
            sess.next_allowed = time.perf_counter() + max(_throttle_s(sess), spent)
        # 2. finished outlines: show them if they belong to the latest result
        if sess.outline_future is not None and sess.outline_future.done():
            fut, sess.outline_future = sess.outline_future, None
            analysis, out = fut.result()
            if sess.last_result is not None and analysis is sess.last_result.analysis:
                overlay.set_outlines(sess.scene_name, analysis, out)
                sess.outlined = analysis
        # 3. something changed and the throttle allows: read and start an analysis
        still = not sess.dirty
        if sess.dirty and sess.outline_future is None and now >= sess.next_allowed:
            sess.dirty = False
            sess.started = now
            inp = read_inputs(sess)
            if inp is not None:
                sess.readout.status = "live"
                sess.future = _pool().submit(compute, sess, inp)
                return _POLL_S
            still = True                # noted, but nothing moved (e.g. our colour write)
        # 4. the pose is still: outlines of the latest result (lower priority)
        res = sess.last_result
        if (res is not None and still and sess.outline_future is None
                and sess.outlined is not res.analysis
                and _want_outlines(bpy.data.scenes.get(sess.scene_name))):
            sess.outline_future = _pool().submit(lambda r=res: (r.analysis, outlines_of(sess, r)))
            return _POLL_S
    except Paused as e:
        sess.readout.status = f"paused: {e}"
        bridge.tag_redraw_view3d(("UI",))
    except OsteonError as e:
        sess.readout.status = f"error: {e}"
        bridge.tag_redraw_view3d(("UI",))
    except Exception as e:  # noqa: BLE001 -- keep the timer alive, say what broke
        import traceback

        traceback.print_exc()
        sess.readout.status = f"error: {type(e).__name__}: {e}"
        bridge.tag_redraw_view3d(("UI",))
    if sess.future is not None or sess.outline_future is not None:
        return _POLL_S
    wait = sess.next_allowed - time.perf_counter()
    return max(_POLL_S, min(wait, 0.25)) if sess.dirty else max(_POLL_S, _throttle_s(sess))


# --------------------------------------------------------------------------- handlers


def _on_depsgraph(scene, depsgraph=None):
    """depsgraph_update_post: note relevant changes only (no data reads)."""
    sess = _session
    if sess is None or scene is None or scene.name != sess.scene_name:
        return
    if depsgraph is None:
        sess.dirty = True
        return
    for u in depsgraph.updates:
        idb = u.id
        orig = getattr(idb, "original", None) or idb
        try:
            ptr = orig.as_pointer()
        except ReferenceError:
            continue
        if ptr in sess.watch:
            if u.is_updated_geometry or u.is_updated_transform:
                sess.dirty = True
                if isinstance(orig, bpy.types.Object) and orig.mode == "WEIGHT_PAINT":
                    sess.weights_stale = True
        elif isinstance(orig, bpy.types.Scene):
            key = _settings_key(orig)
            if key != sess.settings_key:
                sess.settings_key = key
                sess.dirty = True


def _on_frame(scene, depsgraph=None):
    """frame_change_post: an animated pose may have moved."""
    sess = _session
    if sess is not None and scene is not None and scene.name == sess.scene_name:
        sess.dirty = True


@persistent
def _on_load_post(*_args):
    """A new file replaces the scene: end the session and drop the overlay data."""
    stop()
    overlay.clear()
    overlay.sync(getattr(bpy.context, "scene", None))


def handlers_installed() -> bool:
    return (_on_depsgraph in bpy.app.handlers.depsgraph_update_post
            or _on_frame in bpy.app.handlers.frame_change_post
            or bpy.app.timers.is_registered(_tick))


def _add_handlers() -> None:
    if _on_depsgraph not in bpy.app.handlers.depsgraph_update_post:
        bpy.app.handlers.depsgraph_update_post.append(_on_depsgraph)
    if _on_frame not in bpy.app.handlers.frame_change_post:
        bpy.app.handlers.frame_change_post.append(_on_frame)
    if not bpy.app.timers.is_registered(_tick):
        # persistent on purpose: Blender must not drop the timer behind our back at a file
        # load (the bpy 4.5 wheel then hangs at exit); our load_post handler removes it.
        bpy.app.timers.register(_tick, first_interval=_POLL_S, persistent=True)


def unregister_handlers() -> None:
    """Remove the live handlers and timer (every copy, should there be several)."""
    for lst, fn in ((bpy.app.handlers.depsgraph_update_post, _on_depsgraph),
                    (bpy.app.handlers.frame_change_post, _on_frame)):
        while fn in lst:
            lst.remove(fn)
    if bpy.app.timers.is_registered(_tick):
        bpy.app.timers.unregister(_tick)


# --------------------------------------------------------------------------- on / off


def start(context, obj=None, arm=None) -> Readout:
    """Switch Live on for the active rigged mesh (or ``obj``/``arm``) of the context's
    scene; runs the first update at once.  Raises OsteonError."""
    global _session
    core.import_engine()
    if obj is None or arm is None:
        obj, arm = bridge.find_target(context)
    stop()
    scene = context.scene
    sess = Session(scene, obj, arm)
    sess.settings_key = _settings_key(scene)
    sess.started = time.perf_counter()
    _session = sess
    try:
        update_now(force=True, depsgraph=context.evaluated_depsgraph_get())
    except OsteonError:
        _session = None
        _last_readout[scene.name] = sess.readout
        raise
    _add_handlers()
    if not bpy.app.background:
        bridge.show_colors_in_viewports()
    return sess.readout


def stop() -> None:
    """Switch Live off: handlers and timer removed, the running job awaited, the last
    readout kept for the panel; the colour layer stays (it is the last result)."""
    global _session
    sess = _session
    _session = None
    unregister_handlers()
    if sess is not None:
        _wait_jobs(sess)
        sess.readout.status = "off"
        _last_readout[sess.scene_name] = sess.readout
        bridge.tag_redraw_view3d(("UI",))


# --------------------------------------------------------------------------- settings


def _get_enabled(self) -> bool:
    return is_live(self.id_data)


def _set_enabled(self, value: bool) -> None:
    scene = self.id_data
    if not value:
        if is_live(scene):
            stop()
        return
    if is_live(scene):
        return
    ctx = bpy.context
    if ctx.scene != scene:
        return
    try:
        start(ctx)
    except OsteonError as e:
        _last_readout[scene.name] = Readout(status=f"error: {e}")
        print(f"osteon live: {e}")


def _on_show_sections(self, context):
    scene = self.id_data
    overlay.sync(scene)
    sess = _session
    if self.show_sections and sess is not None and sess.scene_name == scene.name:
        sess.outlined = None            # the timer computes outlines for the latest result


class OsteonLiveSettings(bpy.types.PropertyGroup):
    enabled: BoolProperty(
        name="Live", get=_get_enabled, set=_set_enabled,
        description="Re-analyse the active rigged mesh whenever its pose or shape changes "
                    "(colours and readout follow the edits)")
    throttle_ms: IntProperty(
        name="Throttle (ms)", default=50, min=0, soft_max=1000, max=10000,
        description="Shortest time between two live updates, ms (an update also waits at "
                    "least as long as the previous one took)")
    show_sections: BoolProperty(
        name="Show sections", default=False, update=_on_show_sections,
        description="Draw the section outlines of the last analysis in the viewport, "
                    "coloured by stress / allowable (weak ones red and thick)")


classes = (OsteonLiveSettings,)


def register() -> None:
    """Property and load handler (the classes are registered by the add-on)."""
    bpy.types.Scene.osteon_live = bpy.props.PointerProperty(type=OsteonLiveSettings)
    if _on_load_post not in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.append(_on_load_post)


def unregister() -> None:
    global _executor
    stop()
    while _on_load_post in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.remove(_on_load_post)
    if _executor is not None:
        _executor.shutdown(wait=True)
        _executor = None
    _last_readout.clear()
    if hasattr(bpy.types.Scene, "osteon_live"):
        del bpy.types.Scene.osteon_live
