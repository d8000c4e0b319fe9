"""The correction as pose-bone scales: apply, restore, read back, bake into the mesh."""

from __future__ import annotations

import numpy as np

from ._math import matrix_np, parent_depth, transform
from .mesh import local_positions

SAVED_POSE_KEY = "osteon_saved_pose"


def pose_scales(arm) -> dict[str, tuple]:
    return {p.name: tuple(p.scale) for p in arm.pose.bones}


def has_saved_pose(arm) -> bool:
    return SAVED_POSE_KEY in arm


def _xz(scale) -> tuple[float, float]:
    """A bone's cross-section scale as (x, z): a number scales both axes."""
    if isinstance(scale, (tuple, list)):
        return float(scale[0]), float(scale[-1])
    return float(scale), float(scale)


def _xyz(scale) -> tuple[float, float, float]:
    """A bone's pose scale factors on its local (x, y, z): a number s is (s, 1, s), a pair
    (x, z) is (x, 1, z), a triple is itself (joint rigs: see :func:`correction_pose_scales`)."""
    if isinstance(scale, (tuple, list)):
        if len(scale) == 3:
            return float(scale[0]), float(scale[1]), float(scale[2])
        return float(scale[0]), 1.0, float(scale[1])
    return float(scale), 1.0, float(scale)


def apply_bone_scales(context, arm, scales: dict, tol: float = 1e-7) -> list[str]:
    """Scale pose bones across their axis (pose scale x and z times s, y kept; a value is s
    for both axes or an (x, z) pair, as ``osteon.Correction.bone_scale_x/_z``) such that
    Blender's armature deformation reproduces the engine's skinning: children of a
    scaled bone do not inherit the scale (``inherit_scale = 'NONE'``) and get a pose
    location that puts their head back where it was, so they keep shape and place.

    The previous state of every touched bone is stored on the armature object
    (ID property ``osteon_saved_pose``) for :func:`restore_pose`.  A previous
    correction is restored first, so applying is idempotent.  Returns the names of
    the bones that were scaled."""
    restore_pose(context, arm)
    bones = arm.data.bones
    pb = arm.pose.bones
    scaled = [n for n, s in scales.items()
              if max(abs(v - 1.0) for v in _xyz(s)) > tol and n in pb]
    if not scaled:
        return []
    children = sorted({c.name for n in scaled for c in bones[n].children},
                      key=lambda n: parent_depth(bones[n]))
    touched = sorted(set(scaled) | set(children))
    saved = {n: {"scale": list(pb[n].scale), "location": list(pb[n].location),
                 "inherit_scale": bones[n].inherit_scale} for n in touched}
    heads = {n: pb[n].matrix.translation.copy() for n in children}
    arm[SAVED_POSE_KEY] = {"bones": saved}
    try:
        for n in scaled:
            kx, ky, kz = _xyz(scales[n])
            sx, sy, sz = pb[n].scale
            pb[n].scale = (sx * kx, sy * ky, sz * kz)
        for n in children:
            bones[n].inherit_scale = "NONE"
        by_depth: dict[int, list[str]] = {}
        for n in children:
            by_depth.setdefault(parent_depth(bones[n]), []).append(n)
        for d in sorted(by_depth):
            context.view_layer.update()
            for n in by_depth[d]:
                p = pb[n]
                m = p.matrix.copy()
                m.translation = heads[n]
                basis = arm.convert_space(pose_bone=p, matrix=m, from_space="POSE", to_space="LOCAL")
                p.location = basis.translation
        context.view_layer.update()
    except Exception:
        restore_pose(context, arm)
        raise
    return scaled


def restore_pose(context, arm) -> bool:
    """Undo :func:`apply_bone_scales`: the user's pose scales, locations, inherit modes."""
    if SAVED_POSE_KEY not in arm:
        return False
    saved = arm[SAVED_POSE_KEY].to_dict().get("bones", {})
    pb = arm.pose.bones
    bones = arm.data.bones
    for n, st in saved.items():
        if n not in pb:
            continue
        pb[n].scale = st["scale"]
        pb[n].location = st["location"]
        bones[n].inherit_scale = st["inherit_scale"]
    del arm[SAVED_POSE_KEY]
    context.view_layer.update()
    return True


def correction_ratios(arm) -> dict[str, tuple]:
    """Per bone, the cross-section scales (x, z) the current correction applies, or
    (x, y, z) where it also scales the bone's Y axis (a joint-rig bone, see
    :func:`correction_pose_scales`)."""
    if SAVED_POSE_KEY not in arm:
        return {}
    saved = arm[SAVED_POSE_KEY].to_dict().get("bones", {})
    out = {}
    for n, st in saved.items():
        p = arm.pose.bones.get(n)
        if p is not None and all(v != 0.0 for v in st["scale"]):
            r = tuple(float(p.scale[k] / st["scale"][k]) for k in range(3))
            if max(abs(v - 1.0) for v in r) > 1e-7:
                out[n] = r if abs(r[1] - 1.0) > 1e-7 else (r[0], r[2])
    return out


def bake_scales_into_mesh(obj, arm, ratios: dict, bone_names: list[str],
                          csr: tuple[np.ndarray, np.ndarray, np.ndarray]) -> np.ndarray:
    """New rest coordinates (mesh object space) with each bone's cross-section scaled
    about its REST axis, blended by normalised weights (zero-weight vertices kept)."""
    data, indices, indptr = csr
    co = local_positions(obj.data)
    v = len(co)
    rows = np.repeat(np.arange(v), np.diff(indptr))
    total = np.zeros(v)
    np.add.at(total, rows, data)
    to_arm = matrix_np(arm.matrix_world.inverted() @ obj.matrix_world)
    from_arm = np.linalg.inv(to_arm)
    pa = transform(co, to_arm)
    delta = np.zeros_like(pa)
    for name, s in ratios.items():
        if name not in bone_names:
            continue
        b = bone_names.index(name)
        sel = indices == b
        if not np.any(sel):
            continue
        r = rows[sel]
        w = data[sel] / np.where(total[r] > 0, total[r], 1.0)
        rest = matrix_np(arm.data.bones[name].matrix_local)
        kx, ky, kz = _xyz(s)
        d = rest @ np.diag([kx, ky, kz, 1.0]) @ np.linalg.inv(rest)
        p = pa[r]
        delta[r] += w[:, None] * (transform(p, d) - p)
    return transform(pa + delta, from_arm)
