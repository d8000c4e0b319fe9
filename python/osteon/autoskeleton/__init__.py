"""Automatic skeleton and skinning weights for unrigged closed meshes (issue 17). Units: mm.

``auto_skeleton(vertices, faces)`` runs these steps, one module each:

0. ``mesh``: check the mesh, weld coincident vertices; ``pieces``: a mesh in several pieces is
   split into the main body (the piece with the largest enclosed volume), the pieces that touch
   or overlap it (eyes, teeth, a beak: joined to it; a limb glued on as an open tube: capped
   and rigged; a long thin closed limb: rigged) and loose pieces (reported).
1. ``curve``: quadric-simplify the main body, collapse the edges of the simplified mesh that
   are short for the limb they lie on (about 10 vertices round every limb: a torso or a palm
   keeps no more than a finger, which is what the skeleton's cost grows with) and compute its
   curve skeleton with pygel3d's local separators (``pygel3d.graph.LS_skeleton_and_map``,
   MIT, Bærentzen & Rotenberg). A low-poly mesh, whose edges are long for their limb, is
   split 1 -> 4 at its edges' midpoints instead of simplified (up to half the target); a split
   piece joined to the body is skeletonised by the level sets of the geodesic distance from
   where it meets the body instead (``curve.front_skeleton``: one Dijkstra).
2. ``tree``: root node (barycentre or base) and the shortest-path tree from it: every loop is
   cut at the point farthest from the root along the skeleton.
3. ``prune``: bumps, end-cap corners and limbs thinner than printable lose their branch.
4. ``junctions``: junction nodes move to the meeting point of their limbs' axes.
5. ``bones``: branches are split into bones where they bend; each end bone stops
   ``END_RATIO`` radii inside its limb's end (``ends``).
6. ``weights``: one-hot binding smoothed on the simplified mesh, interpolated to the full mesh,
   at most 4 bones per vertex; joined pieces take the weights of the body next to them, loose
   pieces their nearest bone.
7. ``thin``: thin branches the simplified mesh lost (a toe, a claw, an ear 1.5-3 mm thick),
   found on the full mesh: a vertex farthest from its bone among its neighbours whose straight
   line to the bone stays inside, and whose part beyond the limb's surface is longer than
   ``spur`` x its width and at least as thick as printable, gets a bone from the bone to it.
   ``piece_tips``: a joined piece too small for bones of its own (a hand glued on as a box, a
   beak) is tested the same way on the union of the pieces and, if it is a limb end, gets a
   bone from the bone it is bound to.
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np
from scipy import sparse

from .._api import Skeleton, _min_thickness
from .assemble import LoosePiecesWarning, rig_pieces
from .bones import make_bones
from .curve import curve_skeleton
from .ends import END_RATIO
from .junctions import recentre_junctions
from .mesh import check_mesh, piece_labels
from .pieces import Pieces, split_pieces
from .prune import prune
from .thin import add_thin_branches
from .tree import Body, make_body, make_tree
from .weights import fill_node_bones, skin_weights

__all__ = ["DETAIL_LEVELS", "END_RATIO", "LoosePiecesWarning", "Pieces", "auto_skeleton",
           "split_pieces"]

#: ``detail=`` names -> vertex count of the simplified mesh the skeleton is computed on.
DETAIL_LEVELS = {"coarse": 800, "medium": 1500, "fine": 3000}


def _check_options(detail, root, up, spur, bend) -> tuple[int, np.ndarray]:
    """(target vertex count, unit up (3,)) from the options; ValueError naming a bad one."""
    if isinstance(detail, str):
        if detail not in DETAIL_LEVELS:
            raise ValueError(f"detail must be one of {sorted(DETAIL_LEVELS)} or a vertex count")
        target = DETAIL_LEVELS[detail]
    else:
        try:
            target = int(detail)
        except (TypeError, ValueError):
            raise ValueError(f"detail must be a name or a vertex count, got {detail!r}") from None
        if target < 50:
            raise ValueError(f"detail must be at least 50 vertices, got {target}")
    if root not in ("centre", "center", "base"):
        raise ValueError(f"root must be 'centre' or 'base', got {root!r}")
    up_v = np.asarray(up, dtype=np.float64).reshape(-1)
    if up_v.shape != (3,) or not np.isfinite(up_v).all() or np.linalg.norm(up_v) == 0:
        raise ValueError(f"up must be a nonzero 3-vector, got {up!r}")
    for name, val in (("spur", spur), ("bend", bend)):
        if not (isinstance(val, (int, float)) and val > 0 and math.isfinite(val)):
            raise ValueError(f"{name} must be a positive number, got {val!r}")
    return target, up_v / np.linalg.norm(up_v)


def _principal_bone(body: Body, inset: float) -> Skeleton:
    """One bone along the principal axis through the barycentre, ``inset`` × the vertices'
    extent along it (a blob: no curve skeleton)."""
    pts = body.v[body.used]
    c = pts.mean(0)
    axis = np.linalg.svd(pts - c, full_matrices=False)[2][0]
    t = (pts - c) @ axis
    return Skeleton([c + axis * t.min() * inset], [c + axis * t.max() * inset], [-1],
                    ["auto_00"])


def _skeleton_and_weights(body: Body, cs, root: str, spur: float, bend: float, smooth: int,
                          min_t: float) -> tuple[Skeleton, np.ndarray]:
    """Steps 2-6 on the welded mesh: (Skeleton, (V,B) dense weights of its vertices)."""
    if len(cs.npos) < 2:  # no curve skeleton (a blob): one bone along the principal axis
        return _principal_bone(body, 0.9), np.ones((len(body.v), 1))
    tree = make_tree(body, cs, root)
    prune(body, tree, spur, min_t)
    recentre_junctions(body, tree)
    bones = make_bones(body, tree, bend)
    if not bones.heads:  # a blob: one bone along the principal axis through the barycentre
        sk = _principal_bone(body, 0.97)
        bones.node_bone[:] = 0
    else:
        sk = Skeleton(np.array(bones.heads), np.array(bones.tails),
                      np.array(bones.parents, np.int64),
                      [f"auto_{i:02d}" for i in range(len(bones.heads))])
    node_bone = fill_node_bones(tree, bones.node_bone)
    full = skin_weights(body, tree, node_bone, sk.num_bones, smooth)
    return add_thin_branches(body, sk, full, spur)


def _rig_one(v: np.ndarray, f: np.ndarray, root: str | np.ndarray, *, target: int,
             deterministic: bool, up: np.ndarray, spur: float, bend: float, smooth: int,
             min_t: float) -> tuple[Skeleton, np.ndarray]:
    """Steps 1-6 on one welded piece ``v`` (V,3) mm, ``f`` (F,3): (Skeleton, (V,B) weights)."""
    cs = curve_skeleton(v, f, target, deterministic, root)
    body = make_body(v, f, up, cs, min_t)
    return _skeleton_and_weights(body, cs, root, spur, bend, smooth, min_t)


def auto_skeleton(
    vertices: Any,
    faces: Any,
    *,
    detail: str | int = "medium",
    root: str = "centre",
    up: Any = (0.0, 0.0, 1.0),
    spur: float = 1.0,
    bend: float = 0.5,
    smooth: int = 4,
    seed: int | None = 0,
    min_thickness: float | None = None,
) -> tuple[Skeleton, sparse.csr_matrix]:
    """A bone skeleton and skinning weights for an unrigged closed mesh.

    Args:
        vertices: (V,3) float, mm. faces: (F,3) int triangles of a closed mesh, in one
            piece or several: pieces touching or overlapping the body join it (the bigger
            ones get bones of their own), loose pieces are bound to their nearest bone and
            reported with a :class:`LoosePiecesWarning`.
        detail: "coarse", "medium" (default), "fine", or a vertex count: the mesh is
            simplified to about this many vertices before skeletonisation (finer = more
            branches for small features, slower).
        root: "centre" (default): the tree is rooted at the skeleton point nearest the mesh's
            barycentre, and bone 0 (parent -1) starts there; "base": at the skeleton point
            nearest the lowest vertex along ``up`` (the base the model stands on).
        up: (3,) the model's up direction for ``root="base"`` (default +Z).
        spur: a leaf branch that sticks out of the body at its junction by less than ``spur``
            × its own width (mm / mm) is pruned: a bump, not a limb.
        bend: a branch is split into bones where it leaves the straight line between its ends
            by more than ``bend`` × its radius (mm / mm).
        smooth: neighbour-averaging rounds on the simplified mesh that blend weights at joints.
        seed: an int (default 0): deterministic -- the same mesh gives the same skeleton and
            weights on every call (pygel3d's local-separator skeleton grown from every vertex,
            ``LS_skeleton_and_map(sampling=False)``; ~3x the CPU time of the sampled one).
            ``None``: pygel3d's multi-scale sampled skeleton (``MSLS_skeleton_and_map``),
            faster but random: GEL draws samples with libc ``rand()`` from one thread per core,
            so the result depends on thread timing and no seed can fix it (bone counts vary
            by 2-3 between runs). pygel3d takes no seed, so any int gives the same result.
        min_thickness: mm (None: 0.8, FDM; pass the material's ``min_thickness_mm``): a leaf
            branch whose limb is thinner than this along most of its length cannot be printed
            and gets no bone (its vertices go to the bone it hangs from).

    Returns:
        (Skeleton, weights): bones in mm (one root bone, parent -1, at the root point; bones
        leaving the root point in other directions are its children), and a (V,B) SciPy CSR
        matrix of weights (rows sum to 1; vertices not used by any face get their nearest bone).

    Raises:
        ValueError: bad arrays, fewer than 4 faces, a flat/open/zero-volume mesh, an unknown
        ``detail`` or ``root``.
    """
    target, up_v = _check_options(detail, root, up, spur, bend)
    min_t = _min_thickness(min_thickness)
    v, f, weld = check_mesh(vertices, faces)
    if seed is not None and not isinstance(seed, (int, np.integer)):
        raise ValueError(f"seed must be an int or None, got {seed!r}")
    rig = functools.partial(_rig_one, target=target, deterministic=seed is not None, up=up_v,
                            spur=spur, bend=bend, smooth=smooth, min_t=min_t)
    if piece_labels(f, len(v))[0] == 1:
        sk, full = rig(v, f, root)
    else:
        sk, full = rig_pieces(v, f, split_pieces(v, f), root, rig, spur, min_t)
    return sk, sparse.csr_matrix(full)[weld]  # (sparse first: 4 of B columns a row)
