"""Step 5: branches -> bones (units: mm).

Branches (paths between the root, junctions and leaves) are split into bones where they bend
(Ramer–Douglas–Peucker, tolerance ``bend`` × the branch's radius); every leaf bone ends inside
its limb's end (``ends.limb_end``), and so does the root's if the root is an end."""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np

from .ends import limb_end
from .tree import Body, Tree


@dataclass
class Bones:
    """Bones as they are made: heads, tails (3,) mm, parents; node_bone (N,): each skeleton
    node's bone (-1: none yet); root_bone: the first bone (-1: none yet)."""

    node_bone: np.ndarray
    heads: list[np.ndarray] = field(default_factory=list)
    tails: list[np.ndarray] = field(default_factory=list)
    parents: list[int] = field(default_factory=list)
    root_bone: int = -1


def rdp(points: np.ndarray, tol: float) -> list[int]:
    """Indices of the Ramer–Douglas–Peucker simplification of a polyline (always keeps ends)."""
    keep = [0, len(points) - 1]
    stack = [(0, len(points) - 1)]
    while stack:
        i, j = stack.pop()
        if j <= i + 1:
            continue
        a, b = points[i], points[j]
        ab = b - a
        L = np.linalg.norm(ab)
        seg = points[i + 1 : j] - a
        if L > 0:
            d = np.linalg.norm(np.cross(seg, ab / L), axis=1)
        else:
            d = np.linalg.norm(seg, axis=1)
        k = int(np.argmax(d))
        if d[k] > tol:
            keep.append(i + 1 + k)
            stack += [(i, i + 1 + k), (i + 1 + k, j)]
    return sorted(set(keep))


def branch_polyline(body: Body, tree: Tree, ch: list[list[int]], start: int, first: int
                    ) -> tuple[list[int], np.ndarray, list[int], list[int]]:
    """The branch from node ``start`` through ``first`` to the next junction or leaf:
    (its nodes, its polyline (K,3) mm with a leaf's end point, bpath: the node of each
    polyline point (points past a limb's end: none), joints: polyline indices that must end
    a bone (the end bone's end before a tip bone))."""
    path = [start, first]
    while len(ch[path[-1]]) == 1:
        path.append(ch[path[-1]][0])
    pts = tree.npos[path].copy()
    end = path[-1]
    bpath = path
    joints: list[int] = []
    if not ch[end]:  # leaf: reach the limb's end, short of its end cap
        stop, k, tipped = limb_end(body, tree, pts, end)
        if len(stop) > 1:  # a joint at the limb's base or a tip bone: the leaf's node goes to
            bpath = [*path[:k], *[end] * len(stop)]  # the last bone
        if tipped:  # the end bone's end, where the tip bone starts
            joints = [k + len(stop) - 2]
        pts = np.vstack([pts[:k], stop])
    if start == tree.root and len(ch[start]) == 1:  # the root is an end: reach it
        d = pts[0] - pts[min(2, len(pts) - 1)]
        if np.linalg.norm(d) > 0:
            stop, k, _ = limb_end(body, tree, pts[::-1], tree.root, tip=False)
            stop = stop[-1:]  # (no joint at the base here: the root end is one bone)
            bpath = [path[0], *path[len(pts) - k :]]  # bpath[0] is never assigned
            joints = [j + 1 - (len(pts) - k) for j in joints]
            pts = np.vstack([stop, pts[len(pts) - k :]])
    return path, pts, bpath, joints


def breakpoints(pts: np.ndarray, tol: float, size: float) -> list[int]:
    """RDP breakpoints of ``pts`` (K,3) mm at tolerance ``tol`` mm, without those that would
    make bones shorter than 1e-3 of the model's ``size``."""
    keep = rdp(pts, tol)
    kept = [keep[0]]
    for k in keep[1:]:
        if np.linalg.norm(pts[k] - pts[kept[-1]]) > 1e-3 * size:
            kept.append(k)
        elif k == keep[-1] and len(kept) > 1:
            kept[-1] = k
    return kept


def add_chain(out: Bones, pts: np.ndarray, kept: list[int], bpath: list[int], pbone: int) -> int:
    """Append the bones ``pts[kept[i]] -> pts[kept[i+1]]`` below bone ``pbone``; returns the
    last one."""
    prev = pbone
    for s0, s1 in itertools.pairwise(kept):
        b = len(out.heads)
        out.heads.append(pts[s0])
        out.tails.append(pts[s1])
        if prev < 0 and out.root_bone >= 0:
            prev = out.root_bone  # further branches leaving the root point hang on bone 0
        out.parents.append(prev)
        if out.root_bone < 0:
            out.root_bone = b
        out.node_bone[bpath[s0 + 1 : s1 + 1]] = b
        prev = b
    return prev


def make_bones(body: Body, tree: Tree, bend: float) -> Bones:
    """Bones along every branch of ``tree``, depth first from the root; branches split where
    they bend by more than ``bend`` × their median radius (mm / mm)."""
    ch = tree.children()
    out = Bones(np.full(len(tree.npos), -1, np.int64))
    stack: list[tuple[int, int]] = [(tree.root, -1)]
    while stack:
        start, pbone = stack.pop()
        for c in ch[start]:
            path, pts, bpath, joints = branch_polyline(body, tree, ch, start, c)
            rad = float(np.median(tree.nradius[path]))
            kept = breakpoints(pts, bend * max(rad, 1e-3 * body.size), body.size)
            if len(kept) >= 2 and joints:  # a tip bone's joint stays, whatever the bend
                kept = sorted({*kept, *(j for j in joints if 0 < j < len(pts) - 1)})
            if len(kept) < 2:
                continue
            stack.append((path[-1], add_chain(out, pts, kept, bpath, pbone)))
    return out
