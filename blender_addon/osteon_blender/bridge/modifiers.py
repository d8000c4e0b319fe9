"""Reinforcement regions (osteon.reinforce) as Blender objects: each region's modifier volume a
wireframe mesh in the collection "osteon modifiers", in scene units (the engine's are mm)."""

from __future__ import annotations

import bpy
import numpy as np

#: the collection the modifier volumes are shown in (replaced at each showing)
COLLECTION = "osteon modifiers"


def show_modifiers(context, r, mm_per_unit: float) -> list:
    """One wireframe mesh object per region in the collection "osteon modifiers" (replacing
    the last ones), in scene units; named by bone and settings."""
    from osteon.slicer3mf import settings_label

    coll = bpy.data.collections.get(COLLECTION)
    if coll is None:
        coll = bpy.data.collections.new(COLLECTION)
        context.scene.collection.children.link(coll)
    for old in list(coll.objects):
        mesh = old.data
        bpy.data.objects.remove(old, do_unlink=True)
        if mesh is not None and mesh.users == 0:
            bpy.data.meshes.remove(mesh)
    made = []
    for reg in r.regions:
        name = f"osteon {reg['bone']}: {settings_label(reg)}"
        mesh = bpy.data.meshes.new(name)
        v = np.asarray(reg["vertices"], dtype=float) / mm_per_unit
        mesh.from_pydata(v.tolist(), [], np.asarray(reg["faces"]).tolist())
        mesh.update()
        obj = bpy.data.objects.new(name, mesh)
        obj.display_type = "WIRE"
        obj.show_in_front = True
        obj["osteon_perimeters"] = int(reg["perimeters"])
        obj["osteon_infill_percent"] = float(100.0 * reg["infill"])
        coll.objects.link(obj)
        made.append(obj)
    return made
