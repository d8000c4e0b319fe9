"""Stress on a section plane of a solved tet mesh: cut the tets, interpolate σ, take σ_nn.
Units: mm, MPa."""

from __future__ import annotations

import numpy as np

# (corner a, mid node, corner b) in CalculiX order
_TET_EDGES = [(0, 4, 1), (1, 5, 2), (2, 6, 0), (0, 7, 3), (1, 8, 3), (2, 9, 3)]




def section_cut(nodes, tets, center, normal, stresses, max_dist=None):
    """Cut the tet mesh by the plane (center, normal) and interpolate nodal stresses.

    Only the connected piece of cut tetrahedra nearest to ``center`` is kept (other body parts
    cut by the same plane are ignored). Returns ``(points (P,3), sigma_nn (K,P))``.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    n = np.asarray(normal, float)
    n = n / np.linalg.norm(n)
    c = np.asarray(center, float)
    s = (nodes - c) @ n
    st = s[tets[:, :4]]
    cut = np.nonzero((st.min(1) < 0) & (st.max(1) > 0))[0]
    if len(cut) == 0:
        return np.zeros((0, 3)), np.zeros((len(stresses), 0))
    T = tets[cut]
    # connected pieces of the cut tets (sharing a node)
    rows = np.repeat(np.arange(len(T)), 4)
    inc = coo_matrix(
        (np.ones(rows.size), (rows, T[:, :4].ravel())), shape=(len(T), len(nodes))
    ).tocsr()
    adj = inc @ inc.T
    _, lab = connected_components(adj, directed=False)
    cen = nodes[T[:, :4]].mean(1)
    inplane = (cen - c) - np.outer((cen - c) @ n, n)
    dist = np.linalg.norm(inplane, axis=1)
    keep = lab == lab[np.argmin(dist)]
    T = T[keep]
    # σ_nn at every node of the kept tets, per load case
    sn = _sigma_nn(stresses, n)  # (K, N)
    pts, vals = [], []
    for a, m, b in _TET_EDGES:
        for u, v in ((T[:, a], T[:, m]), (T[:, m], T[:, b])):
            su, sv = s[u], s[v]
            x = (su < 0) != (sv < 0)
            x &= su != sv
            if not np.any(x):
                continue
            t = su[x] / (su[x] - sv[x])
            pts.append(nodes[u[x]] + t[:, None] * (nodes[v[x]] - nodes[u[x]]))
            vals.append(sn[:, u[x]] * (1 - t) + sn[:, v[x]] * t)
    P = np.concatenate(pts)
    G = np.concatenate(vals, axis=1)
    if max_dist is not None:
        d = np.linalg.norm((P - c) - np.outer((P - c) @ n, n), axis=1)
        P, G = P[d <= max_dist], G[:, d <= max_dist]
    return P, G


def _sigma_nn(stresses, n):
    S = np.asarray(stresses)
    xx, yy, zz, xy, yz, zx = (S[..., k] for k in range(6))
    return (
        xx * n[0] ** 2
        + yy * n[1] ** 2
        + zz * n[2] ** 2
        + 2 * (xy * n[0] * n[1] + yz * n[1] * n[2] + zx * n[2] * n[0])
    )
