"""osteon.select_loose_pieces: select, in Edit Mode, the vertices of the loose pieces (shells
that neither touch nor overlap the held piece: they would fall off the print) the last Analyze
found on the analysed mesh."""

import bpy
import numpy as np

from .. import bridge, state
from ..core import OsteonError
from ._base import OsteonOperator


def loose_vertices(context) -> tuple:
    """(mesh object, (n,) int64 vertex indices of every loose piece) of the last analysis;
    OsteonError when there is none or the mesh changed since."""
    found = state.get(context.scene)
    info = found.loose_pieces if found is not None else None
    if info is None:
        raise OsteonError("No analysis result: run Analyze first")
    obj = context.scene.objects.get(info["object"])
    if obj is None or obj.type != "MESH":
        raise OsteonError(f"The analysed mesh '{info['object']}' is no longer in the scene")
    if len(obj.data.vertices) != info["vertices"]:
        raise OsteonError(f"Mesh '{obj.name}' has {len(obj.data.vertices)} vertices, "
                          f"{info['vertices']} when analysed: run Analyze again")
    pieces = info["pieces"]
    idx = np.concatenate(pieces) if pieces else np.zeros(0, dtype=np.int64)
    return obj, idx


class OSTEON_OT_select_loose_pieces(OsteonOperator, bpy.types.Operator):
    """Select the vertices of the loose pieces (parts touching nothing held: they would fall off
    the print) on the analysed mesh, in Edit Mode"""

    bl_idname = "osteon.select_loose_pieces"
    bl_label = "Select Loose Pieces"

    def run(self, context):
        obj, idx = loose_vertices(context)
        n = len(state.get(context.scene).loose_pieces["pieces"])
        if n == 0:
            return "osteon: no loose pieces (every part touches the held piece)"
        if context.object is not None and context.object.mode != "OBJECT":
            bpy.ops.object.mode_set(mode="OBJECT")
        for o in context.view_layer.objects:
            if o.select_get() and o is not obj:
                o.select_set(False)
        obj.select_set(True)
        context.view_layer.objects.active = obj
        bridge.select_vertices(obj.data, idx)
        bpy.ops.object.mode_set(mode="EDIT")
        context.tool_settings.mesh_select_mode = (True, False, False)
        return (f"osteon: selected {len(idx)} vertices of {n} loose piece{'s' if n != 1 else ''}"
                f" on '{obj.name}'")
