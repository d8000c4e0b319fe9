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

import bpy

from .. import state
from .session import (
    LiveInputs,
    LiveResult,
    Paused,
    Readout,
    Session,
    compute,
    is_live,
    outlines_of,
    publish,
    read_inputs,
    readout,
    session,
    update_now,
)
from .timer import (
    _on_depsgraph,
    _on_frame,
    _on_load_post,
    _tick,
    handlers_installed,
    start,
    stop,
    unregister_handlers,
)
from .timer import shutdown as _shutdown

__all__ = [
    "LiveInputs",
    "LiveResult",
    "Paused",
    "Readout",
    "Session",
    "_on_depsgraph",
    "_on_frame",
    "_on_load_post",
    "_tick",
    "compute",
    "handlers_installed",
    "is_live",
    "outlines_of",
    "publish",
    "read_inputs",
    "readout",
    "register",
    "session",
    "start",
    "stop",
    "unregister",
    "unregister_handlers",
    "update_now",
]


def register(settings_type) -> None:
    """scene.osteon_live (a pointer to ``settings_type``, ui/live_properties'
    OsteonLiveSettings, registered by the add-on with the other classes) and the load
    handler."""
    bpy.types.Scene.osteon_live = bpy.props.PointerProperty(type=settings_type)
    if _on_load_post not in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.append(_on_load_post)


def unregister() -> None:
    _shutdown()
    for st in state.all_states():
        st.live_readout = None
    if hasattr(bpy.types.Scene, "osteon_live"):
        del bpy.types.Scene.osteon_live
