"""Step 6: skinning weights (units: mm).

Each simplified vertex belongs to the bone of its skeleton node; the one-hot binding is smoothed
by a few rounds of neighbour averaging on the simplified mesh (so vertices near a joint blend
the bones meeting there), interpolated back to the full mesh (inverse squared distance, the 4
nearest simplified vertices) and kept to at most 4 bones per vertex, rows summing to 1."""

from __future__ import annotations

import numpy as np
from scipy import sparse

from .tree import Body, Tree


def fill_node_bones(tree: Tree, node_bone: np.ndarray) -> np.ndarray:
    """(N,) bone of each node: nodes with no bone (pruned or skipped) take their tree
    parent's; the root node has at least bone 0."""
    node_bone = node_bone.copy()
    node_bone[tree.root] = max(node_bone[tree.root], 0)
    for _ in range(len(node_bone)):
        missing = np.flatnonzero(node_bone < 0)
        if not len(missing):
            break
        par = tree.parent[missing]
        node_bone[missing] = np.where(par >= 0, node_bone[np.maximum(par, 0)], 0)
    return node_bone


def smoothed_binding(body: Body, sbone: np.ndarray, nb: int, smooth: int) -> np.ndarray:
    """(S,B) weights on the simplified mesh: one-hot ``sbone`` (S,) averaged over neighbours
    ``smooth`` times."""
    ns = len(body.spos)
    sedges = body.sedges
    w = sparse.csr_matrix((np.ones(ns), (np.arange(ns), sbone)), shape=(ns, nb))
    if len(sedges):
        a = sparse.coo_matrix(
            (np.ones(2 * len(sedges)), (np.r_[sedges[:, 0], sedges[:, 1]],
                                        np.r_[sedges[:, 1], sedges[:, 0]])), shape=(ns, ns)
        ).tocsr() + sparse.identity(ns, format="csr")
        a = sparse.diags(1.0 / np.asarray(a.sum(1)).ravel()) @ a
        for _ in range(int(smooth)):
            w = a @ w
    return w.toarray()


def top4(full: np.ndarray) -> np.ndarray:
    """Keep each row's 4 largest weights (ties broken by column), drop those under 1 % (or under half the row's
    largest), renormalise; (V,B) -> (V,B)."""
    nb = full.shape[1]
    if nb > 4:  # (argpartition: exactly 4 stay when weights tie at the 4th largest)
        np.put_along_axis(full, np.argpartition(full, nb - 4, axis=1)[:, : nb - 4], 0.0, axis=1)
    full[full < np.minimum(0.01, 0.5 * full.max(1, keepdims=True))] = 0.0
    full /= full.sum(1, keepdims=True)
    return full


def skin_weights(body: Body, tree: Tree, node_bone: np.ndarray, nb: int, smooth: int
                 ) -> np.ndarray:
    """(V,B) dense weights of the welded mesh's vertices for ``nb`` bones."""
    wd = smoothed_binding(body, node_bone[tree.owner], nb, smooth)
    inv = 1.0 / np.maximum(body.near_d, 1e-6 * body.size) ** 2
    inv /= inv.sum(1, keepdims=True)
    # (V,S) interpolation matrix, k entries a row, times (S,B): V·k·B products, no (V,k,B)
    # temporary (93 k vertices x 4 x 46 bones is 140 MB)
    nv, k = body.near_i.shape
    interp = sparse.csr_matrix((inv.ravel(), body.near_i.ravel(), np.arange(0, nv * k + 1, k)),
                               shape=(nv, len(wd)))
    return top4(np.asarray(interp @ wd))
