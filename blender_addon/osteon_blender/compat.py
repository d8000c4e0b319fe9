"""What differs between the Blender lines the add-on supports (3.4 ... 5.x), in one place.

* Bone selection: up to 4.x it is ``Bone.select`` / ``select_head`` / ``select_tail``;
  Blender 5.0 removed these from ``Bone`` and keeps selection on ``PoseBone.select``
  (Object and Pose Mode) and ``EditBone.select`` (Edit Mode).
"""

from __future__ import annotations

import bpy

# Blender <= 4.x: selection lives on Bone (shared by Object, Pose and Edit Mode on exit)
BONE_HAS_SELECT = "select" in bpy.types.Bone.bl_rna.properties


def set_bone_selected(arm, name: str, state: bool) -> None:
    """Select (``state=True``) or deselect bone ``name`` of armature object ``arm``."""
    if arm.mode == "EDIT":
        eb = arm.data.edit_bones.get(name)
        if eb is not None:
            eb.select = eb.select_head = eb.select_tail = state
        return
    if BONE_HAS_SELECT:
        b = arm.data.bones[name]
        b.select = b.select_head = b.select_tail = state
    else:
        arm.pose.bones[name].select = state


def bone_selected(arm, name: str) -> bool:
    """True when bone ``name`` of armature object ``arm`` is selected."""
    if arm.mode == "EDIT":
        eb = arm.data.edit_bones.get(name)
        return bool(eb is not None and eb.select)
    if BONE_HAS_SELECT:
        return bool(arm.data.bones[name].select)
    return bool(arm.pose.bones[name].select)
