"""What the 3D viewports show: the stress colour layer, Solid shading by that layer, redraws."""

from __future__ import annotations

import bpy
import numpy as np

LAYER = "osteon_stress"


def write_point_colors(mesh, rgba: np.ndarray, name: str = LAYER):
    """Write (V, 4) RGBA into a FLOAT_COLOR point attribute and make it the active
    (and render) colour.  Only this attribute of the mesh is touched."""
    attr = mesh.attributes.get(name)
    if attr is not None and (attr.domain != "POINT" or attr.data_type != "FLOAT_COLOR"):
        mesh.attributes.remove(attr)
        attr = None
    if attr is None:
        attr = mesh.attributes.new(name, "FLOAT_COLOR", "POINT")
    attr.data.foreach_set("color", np.ascontiguousarray(rgba, dtype=np.float32).ravel())
    ca = getattr(mesh, "color_attributes", None)
    if ca is not None:
        if hasattr(ca, "active_color_name"):
            ca.active_color_name = name
        elif hasattr(ca, "active_color"):
            ca.active_color = mesh.color_attributes[name]
        if hasattr(ca, "render_color_index"):
            ca.render_color_index = ca.find(name)
        if hasattr(ca, "active_color_index"):
            ca.active_color_index = ca.find(name)
    mesh.update_tag()
    return attr


def read_point_colors(mesh, name: str = LAYER) -> np.ndarray | None:
    attr = mesh.attributes.get(name)
    if attr is None:
        return None
    out = np.empty(len(attr.data) * 4, dtype=np.float32)
    attr.data.foreach_get("color", out)
    return out.reshape(-1, 4)


def remove_point_colors(mesh, name: str = LAYER) -> bool:
    attr = mesh.attributes.get(name)
    if attr is None:
        return False
    mesh.attributes.remove(attr)
    mesh.update_tag()
    return True


#: the Solid shading colour each 3D viewport had before osteon switched it to the colour
#: attribute: ``space.as_pointer() -> color_type`` (restore_viewport_colors puts it back)
SHADING_BEFORE: dict[int, str] = {}


def _view3d_areas():
    """Every 3D viewport area of the open windows (none headless)."""
    wm = getattr(bpy.context, "window_manager", None)
    for win in getattr(wm, "windows", None) or []:
        for area in win.screen.areas:
            if area.type == "VIEW_3D":
                yield area


def _view3d_spaces():
    for area in _view3d_areas():
        for space in area.spaces:
            if space.type == "VIEW_3D":
                yield space


def show_colors_in_viewports(screen_owner=None):
    """Solid shading shows the colour attribute in every open 3D viewport (UI only); the
    colour setting each had is remembered for :func:`restore_viewport_colors`."""
    for space in _view3d_spaces():
        if space.shading.type == "SOLID" and space.shading.color_type != "VERTEX":
            SHADING_BEFORE[space.as_pointer()] = space.shading.color_type
            space.shading.color_type = "VERTEX"


def restore_viewport_colors() -> int:
    """Put back the Solid shading colour osteon replaced (Reset); returns how many viewports
    changed.  A viewport the user has set to another colour since is left alone."""
    n = 0
    for space in _view3d_spaces():
        before = SHADING_BEFORE.pop(space.as_pointer(), None)
        if before is not None and space.shading.color_type == "VERTEX":
            space.shading.color_type = before
            n += 1
    SHADING_BEFORE.clear()
    return n


def tag_redraw_view3d(region_types: tuple = ("UI", "WINDOW")):
    """Redraw the sidebars / main regions of every open 3D viewport (UI only; no-op headless)."""
    for area in _view3d_areas():
        for region in area.regions:
            if region.type in region_types:
                region.tag_redraw()
