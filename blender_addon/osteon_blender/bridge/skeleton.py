"""Armatures <-> the engine's skeleton: posed deform bones as arrays, joint-rig segments, and a new armature from a made skeleton (Make skeleton)."""

from __future__ import annotations

from dataclasses import dataclass

import bpy
import numpy as np

from ..errors import OsteonError
from ._math import matrix_np, transform

# A deform bone shorter than this fraction of the skeleton's size has no usable axis.  Blender
# up to 4.x deletes zero-length bones when leaving Edit Mode; 5.2 keeps them (length ~2e-6).
MIN_BONE_LENGTH_REL = 1e-5


@dataclass
class SkeletonArrays:
    names: list[str]          # deform bones, armature order
    heads: np.ndarray         # (B, 3) world, posed, Blender units
    tails: np.ndarray         # (B, 3)
    parents: np.ndarray       # (B,) int, nearest deform ancestor, -1 = root
    x_axes: np.ndarray | None = None  # (B, 3) world unit X axis of each posed bone (roll)
    bone_axes: np.ndarray | None = None  # (B, 3, 3) world unit X, Y, Z axes of each posed bone
    # joint rigs (osteon.io.joints): the Blender tails before the engine's segments replaced
    # them, which bones changed, the local axes (scale X, scale Z, length) of each bone, and
    # (B, 3) world direction of the local axis each bone scales across (its "length" slot),
    # passed to osteon.correct as bone_long_axes
    blender_tails: np.ndarray | None = None
    segment_changed: np.ndarray | None = None
    scale_slots: np.ndarray | None = None
    long_axes: np.ndarray | None = None


def skeleton_arrays(arm) -> SkeletonArrays:
    """Posed deform bones of an armature object in world space."""
    bones = arm.data.bones
    deform = [b.name for b in bones if b.use_deform]
    if not deform:
        raise OsteonError(f"Armature '{arm.name}' has no deform bones")
    idx = {n: i for i, n in enumerate(deform)}
    nb = len(deform)
    pb = arm.pose.bones
    # every pose bone's head, tail and matrix in three bulk reads (float32, as Blender keeps
    # them), then the deform bones' rows: per-bone reads cost ~15 us a bone (x_axis & co. are
    # Python properties)
    n = len(pb)
    rows = np.array([pb.find(name) for name in deform], dtype=np.intp)
    if (rows < 0).any():       # the pose is not rebuilt yet (bones just added)
        missing = deform[int(np.flatnonzero(rows < 0)[0])]
        raise OsteonError(f"Armature '{arm.name}': bone '{missing}' has no pose yet; leave "
                          "Edit Mode or update the scene and try again")
    head_all = np.empty((n, 3), dtype=np.float32)
    tail_all = np.empty((n, 3), dtype=np.float32)
    mat_all = np.empty((n, 4, 4), dtype=np.float32)   # column-major: mat_all[i, j] = column j
    pb.foreach_get("head", head_all.ravel())
    pb.foreach_get("tail", tail_all.ravel())
    pb.foreach_get("matrix", mat_all.ravel())
    head = head_all[rows].astype(np.float64)
    tail = tail_all[rows].astype(np.float64)
    # PoseBone.x_axis (y, z) = matrix.to_3x3() @ unit vector: the column itself, summed from
    # +0.0 (a -0.0 becomes +0.0); the same here
    axes = (mat_all[rows, :3, :3] + np.float32(0.0)).astype(np.float64)
    x_axes = axes[:, 0].copy()
    parents = np.full(nb, -1, dtype=np.int64)
    for i, name in enumerate(deform):
        anc = bones[name].parent
        while anc is not None and anc.name not in idx:
            anc = anc.parent
        if anc is not None:
            parents[i] = idx[anc.name]
    mw = matrix_np(arm.matrix_world)
    head_w, tail_w = transform(head, mw), transform(tail, mw)
    _check_bone_lengths(arm.name, deform, head_w, tail_w)
    x_world = x_axes @ mw[:3, :3].T
    x_world /= np.linalg.norm(x_world, axis=1, keepdims=True)
    axes_w = axes @ mw[:3, :3].T
    axes_w /= np.linalg.norm(axes_w, axis=2, keepdims=True)
    return SkeletonArrays(deform, head_w, tail_w, parents, x_world, axes_w)


def use_joint_segments(sk: SkeletonArrays, vertices: np.ndarray, weights) -> SkeletonArrays:
    """Give the engine the bone segments a joint rig means (FBX/glTF imports: bones with
    arbitrary tails), through the wheel's one function ``osteon.io.joints.joint_segments``;
    a rig whose bones end at their children's heads is left as it is.  ``vertices`` (V, 3)
    world, same units as ``sk``; ``weights`` (V, B).  Updates ``sk`` in place: ``tails`` become
    the segments' ends, ``x_axes`` the local axis that carries the correction's scale X,
    ``scale_slots`` which local axes get (scale X, scale Z, 1) (see
    :func:`correction_pose_scales`) and ``long_axes`` the local axis that keeps scale 1, which
    the engine's correction scales across (``osteon.correct(bone_long_axes=...)``) so that the
    pose scales reproduce its vertices exactly."""
    from osteon.io import joints

    new_tails, changed = joints.joint_segments(sk.heads, sk.tails, sk.parents, vertices, weights)
    sk.blender_tails = sk.tails
    sk.segment_changed = changed
    if changed.any():
        _check_bone_lengths("(segments of the joint rig)", sk.names, sk.heads, new_tails)
        sk.tails = new_tails
        if sk.bone_axes is not None:
            sk.x_axes, sk.scale_slots = joints.cross_section_axes(new_tails - sk.heads,
                                                                  sk.bone_axes)
            sk.long_axes = sk.bone_axes[np.arange(len(sk.names)), sk.scale_slots[:, 2]]
    return sk


def correction_pose_scales(sk: SkeletonArrays, scale_x, scale_z) -> dict[str, tuple]:
    """Per bone name, the pose scale factors (x, y, z) on the bone's own local axes that
    reproduce the engine's cross-section scales: (scale X, 1, scale Z) for a bone whose Y axis is
    its segment; for a joint-rig bone whose segment lies along another local axis, that axis
    gets 1 and the two others the scales (``scale_slots``)."""
    out = {}
    for i, n in enumerate(sk.names):
        v = [1.0, 1.0, 1.0]
        slots = (0, 2, 1) if sk.scale_slots is None else tuple(int(k) for k in sk.scale_slots[i])
        v[slots[0]] = float(scale_x[i])
        v[slots[1]] = float(scale_z[i])
        out[n] = tuple(v)
    return out


def _check_bone_lengths(arm_name: str, names: list[str], head: np.ndarray,
                        tail: np.ndarray) -> None:
    """OsteonError naming the first deform bone whose (posed, world) length is below
    ``MIN_BONE_LENGTH_REL`` times the skeleton's largest extent (Blender units)."""
    length = np.linalg.norm(tail - head, axis=1)
    size = float(np.ptp(np.concatenate([head, tail]), axis=0).max())
    short = np.flatnonzero(~(length > MIN_BONE_LENGTH_REL * size))
    if short.size:
        i = int(short[0])
        raise OsteonError(f"Bone '{names[i]}' of armature '{arm_name}' has (nearly) zero length "
                          f"({length[i]:.3g} Blender units): a bone needs a head and a tail "
                          f"apart to have an axis; delete or lengthen it")


def build_armature(context, name: str, heads: np.ndarray, tails: np.ndarray,
                   parents: np.ndarray, names: list[str]):
    """A new Armature object (at the world origin) with one bone per row: ``heads``/``tails``
    (B, 3) world, Blender units; ``parents`` (B,) int, -1 = root.  Bones are made in Edit
    Mode (bpy has no other way); the loop is over bones (tens), not vertices."""
    data = bpy.data.armatures.new(name)
    arm = bpy.data.objects.new(name, data)
    context.collection.objects.link(arm)
    prev_active = context.view_layer.objects.active
    context.view_layer.objects.active = arm
    bpy.ops.object.mode_set(mode="EDIT")
    try:
        ebs = [data.edit_bones.new(n) for n in names]
        for i, eb in enumerate(ebs):
            eb.head = tuple(float(x) for x in heads[i])
            eb.tail = tuple(float(x) for x in tails[i])
            eb.use_deform = True
        for i, p in enumerate(np.asarray(parents, int)):
            if p >= 0:
                ebs[i].parent = ebs[p]
    finally:
        bpy.ops.object.mode_set(mode="OBJECT")
    context.view_layer.objects.active = prev_active
    return arm


def bind_armature(context, obj, arm, auto_weights: bool = False):
    """An Armature modifier on ``obj`` using ``arm``.  ``auto_weights``: Blender's own
    automatic (bone heat) weights via ``parent_set(type='ARMATURE_AUTO')``, which also parents
    the mesh to the armature and makes the modifier."""
    if auto_weights:
        for o in context.view_layer.objects:
            o.select_set(False)
        obj.select_set(True)
        arm.select_set(True)
        context.view_layer.objects.active = arm
        res = bpy.ops.object.parent_set(type="ARMATURE_AUTO")
        context.view_layer.objects.active = obj
        if "FINISHED" not in res:
            raise OsteonError("Blender's automatic weights failed (parent_set ARMATURE_AUTO)")
        return next(m for m in obj.modifiers if m.type == "ARMATURE")
    mod = obj.modifiers.new(name="Armature", type="ARMATURE")
    mod.object = arm
    return mod
