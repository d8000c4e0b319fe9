"""Live mode's timer and handlers: when to update (throttle, worker thread, depsgraph and frame
handlers, file loads) and switching Live on and off (:func:`start`, :func:`stop`)."""

from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor

import bpy
from bpy.app.handlers import persistent

from .. import bridge, core, overlay, state
from ..core import OsteonError
from .session import (
    Paused,
    Readout,
    Session,
    _set_session,
    _settings_key,
    _wait_jobs,
    _want_outlines,
    complete_report,
    compute,
    outlines_of,
    publish,
    read_inputs,
    update_now,
)

_executor: ThreadPoolExecutor | None = None


def _pool() -> ThreadPoolExecutor:
    global _executor
    if _executor is None:
        _executor = ThreadPoolExecutor(max_workers=1, thread_name_prefix="osteon-live")
    return _executor


# --------------------------------------------------------------------------- timer


def _throttle_s(sess: Session) -> float:
    scene = bpy.data.scenes.get(sess.scene_name)
    s = getattr(scene, "osteon_live", None) if scene is not None else None
    return max(0.0, (s.throttle_ms if s is not None else 50) / 1000.0)


_POLL_S = 0.01


def _tick():
    """bpy.app.timers callback; returns the seconds until the next call (None = stop)."""
    sess = state.live_session()
    if sess is None:
        return None
    now = time.perf_counter()
    published = False
    try:
        # 1. a finished analysis: publish it
        if sess.future is not None:
            if not sess.future.done():
                return _POLL_S
            fut, sess.future = sess.future, None
            res = fut.result()                      # OsteonError -> readout below
            publish(sess, res)
            published = True
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
        # 4. the pose is still: the latest report's section rows (not in the tick that
        # published it: a pose being dragged goes on), then its outlines (lower priority)
        if still and not published and sess.future is None:
            complete_report(sess)
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
    sess = state.live_session()
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
    sess = state.live_session()
    if sess is not None and scene is not None and scene.name == sess.scene_name:
        sess.dirty = True


@persistent
def _on_load_post(*_args):
    """A new file replaces the scene: end the session, forget the old file's results (a scene
    of the new file may have the same name) and drop the overlay data."""
    stop()
    state.clear()
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
    core.import_engine()
    if obj is None or arm is None:
        obj, arm = bridge.find_target(context)
    stop()
    scene = context.scene
    sess = Session(scene, obj, arm)
    sess.settings_key = _settings_key(scene)
    sess.started = time.perf_counter()
    _set_session(scene.name, sess)
    try:
        update_now(force=True, depsgraph=context.evaluated_depsgraph_get())
    except OsteonError:
        _set_session(scene.name, None)
        state.of(scene).live_readout = sess.readout
        raise
    _add_handlers()
    if not bpy.app.background:
        bridge.show_colors_in_viewports()
    return sess.readout


def stop() -> None:
    """Switch Live off: handlers and timer removed, the running job awaited, the last
    readout kept for the panel; the colour layer stays (it is the last result)."""
    sess = state.live_session()
    if sess is not None:
        _set_session(sess.scene_name, None)
    unregister_handlers()
    if sess is not None:
        _wait_jobs(sess)
        complete_report(sess)           # the panel keeps a whole report
        sess.readout.status = "off"
        state.of(sess.scene_name).live_readout = sess.readout
        bridge.tag_redraw_view3d(("UI",))


def shutdown() -> None:
    """Switch Live off and stop the worker thread (unregister)."""
    global _executor
    stop()
    while _on_load_post in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.remove(_on_load_post)
    if _executor is not None:
        _executor.shutdown(wait=True)
        _executor = None
