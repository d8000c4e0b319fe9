"""The first window's 3D viewport, for the scripts that drive a real Blender window
(``ui_screenshots.py``, ``overlay_screenshot.py``, ``bench/bench_gui_cancel.py``)."""

from __future__ import annotations

import bpy


def view3d(make: bool = False):
    """(window, 3D-viewport area, its WINDOW region, its UI (sidebar) region or None) of the
    first window. ``make``: turn the first area into a 3D viewport when there is none;
    otherwise a missing viewport raises RuntimeError."""
    win = bpy.context.window_manager.windows[0]
    area = next((a for a in win.screen.areas if a.type == "VIEW_3D"), None)
    if area is None:
        if not make:
            raise RuntimeError("no 3D viewport")
        area = win.screen.areas[0]
        area.type = "VIEW_3D"
    regions = {r.type: r for r in area.regions}
    return win, area, regions["WINDOW"], regions.get("UI")
