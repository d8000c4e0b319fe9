"""Step 3: prune bumps, end-cap corners and limbs too thin to print (units: mm).

A leaf branch whose tip (the farthest surface point beyond the leaf) lies less than ``spur`` ×
the branch's width beyond the body's surface at its junction is a bump of the body, not a limb;
a leaf node much thinner than its parent and owning fewer vertices (a node in a corner of a
limb's end) is folded into its parent; a leaf branch thinner than printable along most of its
length loses its bone. Pruning repeats until nothing changes."""

from __future__ import annotations

import numpy as np

from .ends import leaf_direction, tip_extent
from .thickness import local_thickness, printable
from .tree import Body, Tree


def _is_end_corner(tree: Tree, leaf: int) -> bool:
    """A leaf node in a corner of a limb's end: under half its parent's radius and owning fewer
    simplified vertices (the tip is still reached by the end bone, see ``ends.limb_end``)."""
    par = int(tree.parent[leaf])
    return bool(par >= 0 and tree.nradius[leaf] < 0.5 * tree.nradius[par]
                and (tree.owner == leaf).sum() < (tree.owner == par).sum())


def leaf_branch(tree: Tree, ch: list[list[int]], leaf: int) -> tuple[list[int], int]:
    """The nodes from ``leaf`` back to (not including) the junction it hangs from, and that
    junction (-1 if the branch reaches the root: a limb by definition, never pruned)."""
    parent = tree.parent
    path = [leaf]
    while parent[path[-1]] >= 0 and len(ch[parent[path[-1]]]) == 1:
        path.append(int(parent[path[-1]]))
        if path[-1] == tree.root:
            break
    junction = int(parent[path[-1]])
    if junction < 0 or path[-1] == tree.root:
        return path, -1
    if len(ch[junction]) < 2 and junction != tree.root:
        return path, -1
    return path, junction


def _prune_round(body: Body, tree: Tree, spur: float, min_t: float) -> bool:
    """One pass over the leaves; True if the tree changed."""
    ch = tree.children()
    thin: list[tuple[list[int], int]] = []
    for leaf in np.flatnonzero(tree.alive):
        leaf = int(leaf)
        if ch[leaf] or leaf == tree.root:
            continue
        if _is_end_corner(tree, leaf):
            tree.fold(leaf, int(tree.parent[leaf]))
            return True
        path, junction = leaf_branch(tree, ch, leaf)
        if junction < 0:
            continue
        reach = np.linalg.norm(tree.npos[leaf] - tree.npos[junction]) + tip_extent(
            body, tree, leaf, leaf_direction(body, tree, leaf)
        )
        # The branch's own width: twice the median radius of its nodes (mm).
        r_med = float(np.median(tree.nradius[path]))
        width = float(local_thickness(r_med))
        if not printable(r_med, min_t):  # thinner than printable along most of its length
            thin.append((path, junction))
        elif reach - tree.nradius[junction] < spur * width and not thin:
            # a bump: sticks out of the body by less than spur x its own width
            for p in path:
                tree.fold(p, junction)
            return True
    # Limbs too thin to print get no bone: all of this round's at once (pruning one by one
    # would leave the last sibling hanging on as part of its parent's limb).
    for path, junction in thin:
        for p in path:
            tree.fold(p, junction)
    return bool(thin)


def prune(body: Body, tree: Tree, spur: float, min_t: float) -> None:
    """Prune ``tree`` in place until nothing changes (``spur`` mm/mm, ``min_t`` mm)."""
    while _prune_round(body, tree, spur, min_t):
        pass
