"""Joint rigs → bone segments: the one place that decides which segment a bone stands for.

FBX and glTF rigs store joints; Blender turns each joint into a bone whose tail is arbitrary
(all pointing up, or sticking out of the mesh).  The engine needs the segment the joint rig
means:

* a bone whose tail meets one of its children's heads is a real bone segment: kept;
* otherwise (a joint rig) the segment runs from the joint to its child joint; with several
  children, to the child whose direction best matches the bone's own skinning domain (the
  weighted centroid of its vertices seen from the joint);
* a leaf (no child apart from the joint itself) runs along its own skinning domain: from the
  joint in the direction of the domain's centroid (its principal axis if the centroid sits on
  the joint), :data:`LEAF_FACTOR` of the domain's weighted mean distance along it, never less
  than :data:`NEAR_REL` of the rig's size (:data:`LEAF_REACH`; the
  farthest vertex made the last sections tiny caps around the tip, cut off-centre, whose
  stresses were nonsense: 7.7e30 MPa on the RigNet dog's leaf, against 25.2 MPa with the mean);
* a bone with neither a child nor weights keeps its tail.

Whether the armature is a joint rig is decided once for the whole rig: a rig is a *bone rig*
(nothing changes) when at least half of its bones that have children end at a child's head.

bpy-free; used by the Blender add-on's bridge (``bridge.skeleton_arrays``) and by the readers'
tests.  Units: whatever the inputs use (Blender units, or mm).
"""

from __future__ import annotations

import numpy as np

#: a tail within this fraction of the rig's size of a child's head "meets" it
MEET_REL = 1e-3
#: a child joint closer than this fraction of the rig's size to its parent joint does not
#: give the parent a direction (RigNet ``*_dup_*`` joints, Blender's FBX end bones)
NEAR_REL = 5e-3
#: how far a leaf runs along its domain: "centroid" (the weighted mean distance; the
#: domain's outer half, thin and least loaded, is not cut) or "farthest"
LEAF_REACH = "centroid"
#: the leaf's segment is this fraction of that reach (a leaf is often a tapering, curved tip
#: (ear, tail): a segment to its centroid can leave the mesh, whose off-centre sections give
#: nonsense stresses)
LEAF_FACTOR = 0.5


def _children(parents: np.ndarray) -> list[list[int]]:
    kids: list[list[int]] = [[] for _ in range(len(parents))]
    for b, p in enumerate(parents):
        if p >= 0:
            kids[int(p)].append(b)
    return kids


def is_joint_rig(heads, tails, parents, meet_rel: float = MEET_REL) -> bool:
    """True when fewer than half of the bones that have children end at a child's head."""
    heads = np.asarray(heads, dtype=np.float64)
    tails = np.asarray(tails, dtype=np.float64)
    kids = _children(np.asarray(parents, dtype=np.int64))
    size = float(np.ptp(np.concatenate([heads, tails]), axis=0).max()) or 1.0
    with_kids = [b for b in range(len(heads)) if kids[b]]
    if not with_kids:
        return False
    meet = sum(1 for b in with_kids
               if min(np.linalg.norm(heads[c] - tails[b]) for c in kids[b]) <= meet_rel * size)
    return meet < 0.5 * len(with_kids)


def _domains(weights, nb: int):
    """Per bone, (rows, weights) of its weighted vertices, from CSR-like (anything with
    ``indptr``, ``indices``, ``data``; bone = column) or dense (V, B) weights."""
    if hasattr(weights, "indptr") and hasattr(weights, "indices"):
        if hasattr(weights, "tocsr"):
            weights = weights.tocsr()
        indptr = np.asarray(weights.indptr, dtype=np.int64)
        col = np.asarray(weights.indices, dtype=np.int64)
        data = np.asarray(weights.data, dtype=np.float64)
        rows = np.repeat(np.arange(len(indptr) - 1), np.diff(indptr))
        order = np.argsort(col, kind="stable")
        bounds = np.searchsorted(col[order], np.arange(nb + 1))
        return [(rows[order[bounds[b]:bounds[b + 1]]], data[order[bounds[b]:bounds[b + 1]]])
                for b in range(nb)]
    w = np.asarray(weights, dtype=np.float64)
    out = []
    for b in range(nb):
        r = np.flatnonzero(w[:, b] > 0)
        out.append((r, w[r, b]))
    return out


def joint_segments(heads, tails, parents, vertices=None, weights=None, *,
                   force: bool | None = None, meet_rel: float = MEET_REL,
                   near_rel: float = NEAR_REL) -> tuple[np.ndarray, np.ndarray]:
    """The tails (B, 3) the engine should use, and a (B,) bool mask of the bones changed.

    ``heads``, ``tails`` (B, 3), ``parents`` (B,) int (-1 = root); ``vertices`` (V, 3) and
    ``weights`` (V, B) (scipy.sparse or dense; ``None``: leaves keep their tails).
    ``force``: True treats the rig as a joint rig, False leaves it alone, None decides with
    :func:`is_joint_rig`."""
    heads = np.asarray(heads, dtype=np.float64).reshape(-1, 3)
    tails = np.asarray(tails, dtype=np.float64).reshape(-1, 3)
    parents = np.asarray(parents, dtype=np.int64).reshape(-1)
    out = tails.copy()
    nb = len(heads)
    if force is None:
        force = is_joint_rig(heads, tails, parents, meet_rel)
    if not force or nb == 0:
        return out, np.zeros(nb, bool)
    pts = heads if vertices is None else np.concatenate([heads, np.asarray(vertices, float)])
    size = float(np.ptp(pts, axis=0).max()) or 1.0
    near = near_rel * size
    kids = _children(parents)
    vertices = None if vertices is None else np.asarray(vertices, dtype=np.float64)
    domains = (_domains(weights, nb) if vertices is not None and weights is not None
               else None)
    for b in range(nb):
        h = heads[b]
        far = [c for c in kids[b] if np.linalg.norm(heads[c] - h) > near]
        rows = w = None
        if domains is not None:
            rows, w = domains[b]
            keep = w > 0
            rows, w = rows[keep], w[keep]
        if len(far) == 1:
            out[b] = heads[far[0]]
            continue
        centroid_dir = None
        if rows is not None and len(rows):
            c = (w[:, None] * vertices[rows]).sum(0) / w.sum()
            if np.linalg.norm(c - h) > near:
                centroid_dir = (c - h) / np.linalg.norm(c - h)
        if len(far) > 1:
            dirs = np.array([(heads[c] - h) / np.linalg.norm(heads[c] - h) for c in far])
            if centroid_dir is not None:
                out[b] = heads[far[int(np.argmax(dirs @ centroid_dir))]]
            else:
                out[b] = heads[far].mean(0)
            continue
        # a leaf: along its own skinning domain
        if rows is None or len(rows) == 0:
            continue
        p = vertices[rows]
        d = centroid_dir
        if d is None:  # centroid on the joint: the domain's principal axis, to its far side
            q = p - p.mean(0)
            _, _, vt = np.linalg.svd(q * np.sqrt(w)[:, None], full_matrices=False)
            d = vt[0]
            t = (p - h) @ d
            if np.abs(t.min()) > np.abs(t.max()):
                d = -d
        t = (p - h) @ d
        reach = LEAF_FACTOR * (float((w * t).sum() / w.sum()) if LEAF_REACH == "centroid"
                               else float(t.max()))
        # never shorter than `near`: a domain wrapped around its joint (a paw around the ankle)
        # has almost no reach, and Blender's arbitrary tail (up the leg) is worse than a stub
        out[b] = h + max(reach, near) * d
    changed = np.linalg.norm(out - tails, axis=1) > meet_rel * size
    return out, changed


def cross_section_axes(segments: np.ndarray, bone_axes: np.ndarray) -> tuple[np.ndarray,
                                                                             np.ndarray]:
    """For each bone, which of its own local axes (X, Y, Z) carry the cross-section scales of a
    segment that is not its Y axis.

    ``segments`` (B, 3) tail - head of the engine's segments; ``bone_axes`` (B, 3, 3) world
    directions of each bone's local X, Y, Z (rows).  Returns ``x_axes`` (B, 3): the local axis
    the engine's scale X is measured about (pass as ``bone_x_axes``), and ``slots`` (B, 3) int:
    the local axis indices that receive (scale X, scale Z, 1) — the axis closest to the segment
    gets 1 (it is the length), the other two the cross-section scales."""
    seg = np.asarray(segments, dtype=np.float64)
    seg = seg / np.linalg.norm(seg, axis=1, keepdims=True)
    ax = np.asarray(bone_axes, dtype=np.float64)
    along = np.abs(np.einsum("bij,bj->bi", ax, seg))  # (B, 3) |cos| of each local axis
    long = np.argmax(along, axis=1)
    table = {0: (1, 2, 0), 1: (0, 2, 1), 2: (0, 1, 2)}
    slots = np.array([table[int(k)] for k in long], dtype=np.int64)
    x_axes = ax[np.arange(len(ax)), slots[:, 0]]
    return x_axes, slots


def joint_rig_bones(positions, joint_parent, skin_rows=None, skin_joints=None, skin_values=None,
                    n_vertices: int = 0, vertices=None, stub: float = 0.05):
    """A joint rig as Blender's FBX/glTF importers make it — one bone per joint, head at the
    joint, tail a ``stub`` (fraction of the rig's size) up +Z (meaningless, like the
    importers') — and the segments :func:`joint_segments` gives it.  For the readers' tests and
    scripts: the same function the add-on's bridge calls, on the same joints.

    Returns ``heads`` (J, 3), ``tails`` (J, 3) (the segments), ``parents`` (J,), ``weights``
    (V, J) scipy.sparse (or None) and ``changed`` (J,) bool."""
    import scipy.sparse as sp

    heads = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    parents = np.asarray(joint_parent, dtype=np.int64)
    size = float(np.ptp(heads, axis=0).max()) or 1.0
    stub_tails = heads + np.array([0.0, 0.0, stub * size])
    w = None
    if skin_rows is not None:
        w = sp.csr_matrix((np.asarray(skin_values, float),
                           (np.asarray(skin_rows, np.int64), np.asarray(skin_joints, np.int64))),
                          shape=(int(n_vertices), len(heads)))
    tails, changed = joint_segments(heads, stub_tails, parents, vertices, w, force=True)
    return heads, tails, parents, w, changed
