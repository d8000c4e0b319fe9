"""The viewport clip range a row click moves, and putting the user's range back (issue 35).

A row click (``ops/select_bone.frame``) stands the view 12 section radii from the section; on
a small model (1 cm in scene units) that is inside Blender's default near clip (0.01) and the
view would be empty, so the click lowers the near clip (and, for a huge model, raises the far
one).  What a user expects after that: the range they had comes back as soon as the view no
longer needs the change, and nothing else of theirs is touched.  So, per 3D viewport:

* the range the user had before the first click that moved it is remembered;
* every click starts again from that range (a click on a large section puts it back);
* it is put back as soon as the view leaves the section -- the view centre moves away from it
  (Home, View Selected, a pan; not an orbit or a zoom around it) -- or the view is zoomed out
  far enough that the user's own range shows it again;
* it is put back when the add-on is disabled; a file saved meanwhile keeps the range its
  view shows (that view is on the section), and loading another file drops the memory (its
  views are its own);
* if the user changes the clip range themselves in the meantime, theirs stays and the old one
  is forgotten.

``fit`` is called by the click; ``check`` (a ``bpy.app.timers`` timer while a range is held)
decides when to put it back.  The rules themselves (:func:`clip_for_view`,
:func:`left_section`) do not touch Blender.
"""

from __future__ import annotations

import bpy
import numpy as np
from bpy.app.handlers import persistent

#: the clip range kept when it has to move: end / start, Blender's default 1000 / 0.01
CLIP_RATIO = 1.0e5
#: seconds between two looks at the held viewports
CHECK_S = 0.5

#: space pointer -> {"user": (start, end), "set": (start, end), "centre": (3,),
#: "distance": framed view distance, "size": model size} (Blender units)
_held: dict[int, dict] = {}


def clip_for_view(start: float, end: float, distance: float, size: float) -> tuple[float, float]:
    """The clip range (start, end) that shows a view ``distance`` from its centre on a model
    of ``size`` (Blender units), moved from the range (``start``, ``end``) only where that
    range would cut it: a near clip over a quarter of the distance comes down to a twentieth
    of it (keeping Blender's default far / near ratio), a far clip short of the model's far
    side goes out past it.  Returns (start, end) unchanged when nothing needs to move."""
    if start > 0.25 * distance:
        start = 0.05 * distance
        end = min(end, max(start * CLIP_RATIO, distance + 4.0 * size))
    if end < distance + 2.0 * size:
        end = distance + 4.0 * size
    return start, end


def left_section(held: dict, location, distance: float) -> bool:
    """Whether a view centred at ``location`` (3,), ``distance`` from it, has left the held
    section: its centre is more than half the (framed or current, the larger) view distance
    away from the section (the section is off-centre, out of sight), or the user's own range
    is enough at this distance (zoomed out: nothing to keep the moved range for)."""
    away = float(np.linalg.norm(np.asarray(location, dtype=np.float64) - held["centre"]))
    if away > 0.5 * max(float(distance), held["distance"]):
        return True
    return clip_for_view(*held["user"], float(distance), held["size"]) == held["user"]


def _same(a: tuple[float, float], b: tuple[float, float]) -> bool:
    """Clip ranges equal as Blender stores them (float32)."""
    return bool(np.allclose(np.float32(a), np.float32(b), rtol=1e-6, atol=0.0))


def _range(space) -> tuple[float, float]:
    return float(space.clip_start), float(space.clip_end)


def _set(space, clip: tuple[float, float]) -> tuple[float, float]:
    """Set a viewport's clip range (the far clip first when it grows: Blender keeps
    start < end); returns the range as Blender stored it."""
    start, end = clip
    if end > space.clip_end:
        space.clip_end, space.clip_start = end, start
    else:
        space.clip_start, space.clip_end = start, end
    return _range(space)


def user_range(space) -> tuple[float, float]:
    """The viewport's clip range as the user set it (the held one if a click moved it and
    the user has not changed it since)."""
    held = _held.get(space.as_pointer())
    if held is not None and _same(_range(space), held["set"]):
        return held["user"]
    return _range(space)


def fit(space, centre, distance: float, size: float) -> None:
    """A click frames ``centre`` (3,) at ``distance`` on a model of ``size`` (Blender units)
    in the 3D viewport ``space``: its clip range becomes :func:`clip_for_view` of the user's
    range, which is held (to put back) while it differs from it."""
    key = space.as_pointer()
    user = user_range(space)
    clip = clip_for_view(*user, float(distance), float(size))
    if _same(clip, user):
        if key in _held:
            _set(space, user)
            del _held[key]
        return
    _held[key] = {"user": user, "set": _set(space, clip),
                  "centre": np.asarray(centre, dtype=np.float64).copy(),
                  "distance": float(distance), "size": float(size)}
    # (background Blender runs no timers: scripts and tests call check() themselves)
    if not bpy.app.background and not bpy.app.timers.is_registered(_tick):
        bpy.app.timers.register(_tick, first_interval=CHECK_S)


def held_spaces() -> dict[int, dict]:
    """The viewports whose clip range a click moved (space pointer -> what is held)."""
    return _held


def _spaces():
    """Every 3D viewport space of every screen (pointer -> space): the held ones that still
    exist (a closed area's space is gone: never touched again)."""
    found = {}
    for screen in bpy.data.screens:
        for area in screen.areas:
            if area.type == "VIEW_3D":
                for space in area.spaces:
                    if space.type == "VIEW_3D":
                        found[space.as_pointer()] = space
    return found


def check() -> None:
    """Put back the user's range in every held viewport whose view left its section; forget
    the viewports whose range the user changed, or that are gone."""
    if not _held:
        return
    spaces = _spaces()
    for key in list(_held):
        space, held = spaces.get(key), _held[key]
        if space is None or not _same(_range(space), held["set"]):
            del _held[key]       # gone, or the user set their own range: leave it
            continue
        r3d = space.region_3d
        if r3d is not None and left_section(held, r3d.view_location, r3d.view_distance):
            _set(space, held["user"])
            del _held[key]


def restore_all() -> None:
    """Put back the user's range in every held viewport (the add-on is disabled)."""
    spaces = _spaces()
    for key, held in list(_held.items()):
        space = spaces.get(key)
        if space is not None and _same(_range(space), held["set"]):
            _set(space, held["user"])
    _held.clear()


def _tick():
    try:
        check()
    except ReferenceError:  # a space freed under us: nothing of it to put back
        _held.clear()
    return CHECK_S if _held else None


@persistent
def _on_load_pre(*_args):
    """Another file: its views are its own; the held ranges belong to the old one."""
    _held.clear()


_HANDLERS = (("load_pre", _on_load_pre),)


def register() -> None:
    for name, fn in _HANDLERS:
        handlers = getattr(bpy.app.handlers, name)
        if fn not in handlers:
            handlers.append(fn)


def unregister() -> None:
    try:
        restore_all()
    except ReferenceError:
        _held.clear()
    if bpy.app.timers.is_registered(_tick):
        bpy.app.timers.unregister(_tick)
    for name, fn in _HANDLERS:
        handlers = getattr(bpy.app.handlers, name)
        if fn in handlers:
            handlers.remove(fn)
