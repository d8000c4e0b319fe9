"""Scene objects: which mesh and armature to analyse, and turning objects (Print direction: world matrices, the arrow preview)."""

from __future__ import annotations

import bpy
import numpy as np
from mathutils import Matrix

from ..errors import OsteonError
from ._math import matrix_np, parent_depth


def armature_of(obj) -> bpy.types.Object | None:
    """The armature object of the first enabled Armature modifier of ``obj``."""
    for mod in obj.modifiers:
        if mod.type == "ARMATURE" and mod.object is not None and mod.show_viewport:
            return mod.object
    return None


def meshes_of_armature(arm, scene) -> list:
    return [o for o in scene.objects if o.type == "MESH" and armature_of(o) is arm]


def find_target(context) -> tuple:
    """(mesh object, armature object) for the active object, or OsteonError."""
    obj = context.active_object if hasattr(context, "active_object") else None
    if obj is None:
        obj = getattr(context.view_layer.objects, "active", None)
    if obj is None:
        raise OsteonError("No active object: select a mesh that has an Armature modifier")
    if obj.type == "ARMATURE":
        cands = meshes_of_armature(obj, context.scene)
        if not cands:
            raise OsteonError(f"Armature '{obj.name}' deforms no mesh (no Armature modifier uses it)")
        if len(cands) > 1:
            sel = [o for o in cands if o.select_get()]
            if len(sel) != 1:
                names = ", ".join(sorted(o.name for o in cands))
                raise OsteonError(f"Armature '{obj.name}' deforms several meshes ({names}): "
                                  "make the one to analyse active")
            cands = sel
        obj = cands[0]
    if obj.type != "MESH":
        raise OsteonError(f"Active object '{obj.name}' is a {obj.type.lower()}, not a mesh: "
                          "select a rigged mesh")
    if obj.mode == "EDIT":
        raise OsteonError(f"Mesh '{obj.name}' is in Edit Mode: leave Edit Mode first")
    arm = armature_of(obj)
    if arm is None or arm.type != "ARMATURE":
        raise OsteonError(f"Mesh '{obj.name}' has no Armature modifier with an armature object")
    if len(obj.data.vertices) == 0:
        raise OsteonError(f"Mesh '{obj.name}' has no vertices")
    return obj, arm


def world_matrices(objects) -> dict:
    """name -> a copy of matrix_world, (4, 4) float64, for each object."""
    return {o.name: matrix_np(o.matrix_world).copy() for o in objects}


def set_world_matrices(context, objects, matrices: dict) -> None:
    """Set each object's matrix_world from ``matrices`` (name -> (4, 4)), parents first."""
    for o in sorted(objects, key=parent_depth):
        if o.name in matrices:
            o.matrix_world = Matrix(np.asarray(matrices[o.name], float).tolist())
            context.view_layer.update()


def rotate_objects(context, objects, rotation: np.ndarray, centre: np.ndarray) -> dict:
    """Turn ``objects`` rigidly by ``rotation`` (3, 3) about the world point ``centre`` (3,)
    (Blender units): new matrix_world = T(c) R T(-c) old. An object whose parent is also turned
    follows its parent and is not turned again. Returns the old matrices (name -> (4, 4))."""
    objects = list(objects)
    old = world_matrices(objects)
    t = np.eye(4)
    t[:3, :3] = np.asarray(rotation, float)
    c = np.asarray(centre, float)
    t[:3, 3] = c - t[:3, :3] @ c
    names = {o.name for o in objects}

    def follows(o) -> bool:
        p = o.parent
        while p is not None:
            if p.name in names:
                return True
            p = p.parent
        return False

    new = {o.name: t @ old[o.name] for o in objects if not follows(o)}
    set_world_matrices(context, [o for o in objects if o.name in new], new)
    return old


def arrow_empty(context, name: str, origin, direction, length: float):
    """A single-arrow empty ``name`` at ``origin`` (3,) whose arrow (local +Z) points along
    ``direction`` (3,), ``length`` Blender units long; reused if it exists (a preview, never
    the user's mesh)."""
    ob = bpy.data.objects.get(name)
    if ob is None or ob.type != "EMPTY":
        ob = bpy.data.objects.new(name, None)
    if context.scene.collection.objects.get(ob.name) is None:
        context.scene.collection.objects.link(ob)
    ob.empty_display_type = "SINGLE_ARROW"
    ob.empty_display_size = float(length)
    d = np.asarray(direction, float)
    d = d / np.linalg.norm(d)
    # a rotation taking +Z to d: the transpose of the one taking d to +Z
    from osteon.orientation import rotation_to_z

    m = np.eye(4)
    m[:3, :3] = rotation_to_z(d).T
    m[:3, 3] = np.asarray(origin, float)
    ob.matrix_world = Matrix(m.tolist())
    ob.show_in_front = True
    return ob


def remove_object(name: str) -> None:
    ob = bpy.data.objects.get(name)
    if ob is not None:
        bpy.data.objects.remove(ob, do_unlink=True)
