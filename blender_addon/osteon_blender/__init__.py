"""osteon for Blender: find the parts of a rigged model that will break once printed,
and thicken them along the skeleton.  Sidebar (N) tab "Osteon" in the 3D viewport.

Works as a Blender 4.2+ extension (blender_manifest.toml, bundled wheel) and as a
legacy add-on in Blender 3.4-4.1 (bl_info below).  Units: mm, N, MPa.
"""

import bpy

from . import live, ops, overlay, prefs, state, ui, viewclip
from .ui import live_panel

bl_info = {
    "name": "Osteon: print strength of rigged models",
    "author": "osteon contributors",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > Osteon",
    "description": "Skeleton-sectional stress analysis (MPa) and bone-wise thickening for 3D "
                   "printing",
    "doc_url": "",
    "category": "Mesh",
}

_classes = ui.classes + ops.classes + live_panel.classes + prefs.classes


_atexit_hooked = False


def register():
    global _atexit_hooked
    for cls in _classes:
        bpy.utils.register_class(cls)
    bpy.types.Scene.osteon = bpy.props.PointerProperty(type=ui.properties.OsteonSettings)
    live.register(ui.live_properties.OsteonLiveSettings)  # scene.osteon_live, load_post handler (live mode, issue 7)
    overlay.register()
    viewclip.register()  # load_pre handler: the clip ranges a row click moved (issue 35)
    if not bpy.app.binary_path and not _atexit_hooked:
        # bpy as a Python module (PyPI wheel) hangs at exit while classes are registered
        import atexit

        atexit.register(_unregister_at_exit)
        _atexit_hooked = True


def _unregister_at_exit():
    if hasattr(bpy.types.Scene, "osteon"):
        unregister()


def unregister():
    viewclip.unregister()  # the user's clip ranges back, timer and handler off
    overlay.unregister()  # draw handler off (live mode, issue 7)
    live.unregister()  # live handlers, timer, worker, scene.osteon_live
    if hasattr(bpy.types.Scene, "osteon"):
        del bpy.types.Scene.osteon
    for cls in reversed(_classes):
        if getattr(cls, "is_registered", True):
            bpy.utils.unregister_class(cls)
    state.clear()
