"""Step 4: re-centre junctions on the meeting point of their limbs' axes (units: mm).

A local-separator skeleton puts a junction node at the centroid of a separator, which can sit
off the limbs' axes by a limb's width or more. Move it to the least-squares meeting point of
the axes of the branches that meet there (each axis fitted to the branch's first nodes, at
least two and up to 4 junction radii out), if the axes are not parallel, the point is inside
the mesh and within 3 limb radii; nodes the move leaves behind the junction (on the way back)
are folded into it."""

from __future__ import annotations

import math

import numpy as np

from .tree import Body, Tree

#: a branch as (first node, its nodes out from the junction, whether it runs towards the root)
Branch = tuple[int, list[int], bool]


def branch_nodes(body: Body, tree: Tree, ch: list[list[int]], j: int, first: int,
                 upward: bool) -> list[int]:
    """The nodes of the branch leaving junction ``j`` through ``first``, out to 4 junction
    radii (at least two nodes) or the next junction; ``upward``: towards the root (past the
    root down its other side if the root lies on a limb)."""
    parent, ch_root = tree.parent, tree.root
    hi = 4.0 * max(tree.nradius[j], 1e-3 * body.size)
    out, node, prev, arc = [], first, j, 0.0
    while node >= 0 and tree.alive[node]:
        arc += float(np.linalg.norm(tree.npos[node] - tree.npos[prev]))
        out.append(node)
        if arc >= hi and len(out) >= 2:
            break
        if upward and node == ch_root:  # the root on a limb: go on down its other side
            other = [c for c in ch[node] if c != prev]
            if len(other) != 1:
                break
            upward, prev, node = False, node, other[0]
            continue
        prev = node
        if upward:
            if len(ch[node]) > 1:
                break
            node = int(parent[node])
        elif len(ch[node]) == 1:
            node = ch[node][0]
        else:
            break
    return out


def meeting_point(body: Body, tree: Tree, j: int, branches: list[Branch]
                  ) -> tuple[np.ndarray, list[np.ndarray | None]] | None:
    """The least-squares meeting point (3,) mm of the branches' axes and each branch's axis
    direction (pointing away from ``j``; None for a branch too short to fit), or None if the
    axes are parallel, miss each other, or meet outside the mesh or too far from ``j``."""
    npos, nradius = tree.npos, tree.nradius
    a_sum, b_sum, axes, reach = np.zeros((3, 3)), np.zeros(3), [], nradius[j]
    c_sum, n_axes = 0.0, 0
    for _first, nodes, _up in branches:
        pts = npos[nodes]
        far = np.linalg.norm(pts - npos[j], axis=1) >= nradius[j]
        if far.sum() >= 2:  # nodes inside the junction's ball are bent towards it
            pts = pts[far]
        if len(pts) < 2:
            axes.append(None)
            continue
        c = pts.mean(0)
        d = np.linalg.svd(pts - c, full_matrices=False)[2][0]
        if (c - npos[j]) @ d < 0:
            d = -d  # pointing away from the junction
        proj = np.eye(3) - np.outer(d, d)
        a_sum += proj
        b_sum += proj @ c
        c_sum += c @ proj @ c
        n_axes += 1
        axes.append(d)
        reach = max(reach, float(nradius[nodes].max()))
    if np.linalg.eigvalsh(a_sum)[0] < 0.2:  # fewer than two non-parallel axes
        return None
    x = np.linalg.solve(a_sum, b_sum)
    # the axes must really meet there: RMS distance from x to them under half a radius
    miss = math.sqrt(max(float(x @ a_sum @ x - 2 * x @ b_sum + c_sum), 0.0) / n_axes)
    if (np.linalg.norm(x - npos[j]) > 3.0 * reach or miss > 0.5 * max(nradius[j], 1e-9)
            or body.inner_radius(x)[0] <= 0):
        return None
    return x, axes


def fold_behind(tree: Tree, ch: list[list[int]], j: int, branches: list[Branch],
                axes: list[np.ndarray | None]) -> list[list[int]]:
    """Fold into junction ``j`` the first nodes of each branch that now lie behind it;
    returns the updated children lists."""
    parent, x = tree.parent, tree.npos[j]
    for (_first, nodes, upward), d in zip(branches, axes, strict=True):
        if d is None:
            continue
        for node in nodes[:-1]:
            if (tree.npos[node] - x) @ d >= 0 or node == tree.root or len(ch[node]) > 1 \
                    or (upward and parent[node] < 0):
                break
            if upward:
                parent[j] = parent[node]
            else:
                for c in ch[node]:
                    parent[c] = j
            tree.fold(node, j)
            ch = tree.children()
    return ch


def recentre_junctions(body: Body, tree: Tree) -> None:
    """Move every junction of ``tree`` (3 or more branches) to its limbs' meeting point."""
    ch = tree.children()
    for j in range(len(tree.npos)):
        if not tree.alive[j] or len(ch[j]) + (tree.parent[j] >= 0) < 3:
            continue
        branches = [(c, branch_nodes(body, tree, ch, j, c, False), False) for c in ch[j]]
        if tree.parent[j] >= 0:
            up = int(tree.parent[j])
            branches.append((up, branch_nodes(body, tree, ch, j, up, True), True))
        met = meeting_point(body, tree, j, branches)
        if met is None:
            continue
        x, axes = met
        tree.npos[j] = x
        tree.nradius[j] = body.inner_radius(x)[0]
        ch = fold_behind(tree, ch, j, branches, axes)
        ch = tree.children()
