"""A curved thin branch's axis, traced by the centroids of its cross-sections (units: mm).

The thin step (``thin``) gives a bone to a thin branch whose straight line from its tip c to
its bone's nearest point stays inside the mesh. A curved branch (a claw, a hooked toe, a bent
horn) leaves the mesh along that line. Here its axis is traced from c instead (issue 35):

* the first direction is from c to the centroid of its mesh neighbours (at a tip, the way
  into the branch);
* each step goes ``step`` mm on along the current direction u from the current point p, cuts
  the mesh with the plane through that point perpendicular to u, and takes the cut's loop
  nearest that point: the next point is the loop's centroid (its segments' midpoints weighted
  by their lengths, inside the loop for a convex section, as a limb's section is, however few
  vertices it has), the next direction from p to it;
* the loop must be closed and lie within ``reach`` of the point (reach: the point's distance
  to the bone; a section wider than that is no longer the branch's) and its centroid inside
  the mesh, or the trace fails;
* it stops at the first point whose straight line to its nearest point on the bone stays
  inside the mesh (that point and the bone's point end the axis), or fails after
  ``MAX_STEPS``.

Unlike a geodesic band's centroid (tried before: on a low-poly limb a band holds one or two
vertices of a ring, so its centroid falls outside), a plane section of a limb is its whole
ring, whatever the vertices' spacing along it.
"""

from __future__ import annotations

import numpy as np
from scipy import sparse
from scipy.sparse import csgraph

#: steps per chord (the straight distance from the tip to the bone) and the most steps taken
STEPS_PER_CHORD = 16
MAX_STEPS = 48
#: samples on the line from a trace point to the bone, to test that it stays inside
LINE_SAMPLES = 16

_EDGES = ((0, 1), (1, 2), (2, 0))


def _vertex_faces(body, near) -> sparse.csr_matrix:
    """(V,F) vertex-face incidence of ``body``, built once per ``near``."""
    vf = getattr(near, "vertex_faces", None)
    if vf is None:
        f = body.f
        rows = f.ravel()
        cols = np.repeat(np.arange(len(f)), 3)
        vf = sparse.csr_matrix((np.ones(len(rows), bool), (rows, cols)),
                               shape=(len(body.v), len(f)))
        near.vertex_faces = vf
    return vf


def _section(v: np.ndarray, f: np.ndarray, p: np.ndarray, n: np.ndarray
             ) -> tuple[np.ndarray, bool, float] | None:
    """The loop of the plane through ``p`` (3,) with unit normal ``n`` (3,) cutting the faces
    ``f`` (F,3) of ``v`` nearest ``p``: (its centroid (3,), whether it is closed among ``f``,
    its farthest point's distance from ``p``, mm); None if the plane cuts none of them."""
    s = (v - p) @ n
    s = np.where(s == 0.0, 1e-12, s)  # (a vertex on the plane counts as above it)
    sf = s[f]
    cut = (sf.min(1) < 0) & (sf.max(1) > 0)
    if not cut.any():
        return None
    fc, sc = f[cut], sf[cut]
    pts, keys = [], []
    for a, b in _EDGES:
        crosses = (sc[:, a] < 0) != (sc[:, b] < 0)
        with np.errstate(divide="ignore", invalid="ignore"):  # (sides not crossing: unused)
            t = sc[:, a] / (sc[:, a] - sc[:, b])
            pts.append(v[fc[:, a]] + t[:, None] * (v[fc[:, b]] - v[fc[:, a]]))
        keys.append(np.where(crosses, np.minimum(fc[:, a], fc[:, b]) * (len(v) + 1)
                             + np.maximum(fc[:, a], fc[:, b]), -1))
    pts_all, keys_all = np.stack(pts, 1), np.stack(keys, 1)  # (C,3,3), (C,3)
    has = keys_all >= 0  # two of the three sides of every cut face
    order = np.argsort(~has, axis=1, kind="stable")[:, :2]
    rows = np.arange(len(fc))[:, None]
    ends, ekey = pts_all[rows, order], keys_all[rows, order]  # (C,2,3), (C,2)
    uniq, node = np.unique(ekey.ravel(), return_inverse=True)
    node = node.reshape(-1, 2)
    m = len(uniq)
    graph = sparse.coo_matrix((np.ones(len(node)), (node[:, 0], node[:, 1])), shape=(m, m))
    _k, label = csgraph.connected_components(graph, directed=False)
    mid = ends.mean(1)
    seg = label[node[:, 0]]
    near = seg[np.argmin(np.linalg.norm(mid - p, axis=1))]
    mine = seg == near
    length = np.linalg.norm(ends[mine, 1] - ends[mine, 0], axis=1)
    if length.sum() <= 0:
        return None
    centroid = (mid[mine] * length[:, None]).sum(0) / length.sum()
    degree = np.bincount(node[mine].ravel(), minlength=m)
    closed = bool((degree[degree > 0] == 2).all())
    extent = float(np.linalg.norm(ends[mine] - p, axis=2).max())
    return centroid, closed, extent


def trace_axis(body, near, c: int, a: np.ndarray, b: np.ndarray, step: float
               ) -> np.ndarray | None:
    """The axis (K,3) of the curved branch whose tip is vertex ``c`` of ``body``, from the tip
    to the bone ``a``-``b`` (heads and tails (3,)): the tip, the section centroids, then the
    bone's nearest point to the last one; None if the trace fails (module docstring).
    ``near``: the thin step's ``_Neighbourhood`` (vertex graph, k-d tree)."""
    v = body.v
    ab = b - a
    den = max(float(ab @ ab), 1e-300)

    def on_bone(x: np.ndarray) -> np.ndarray:
        return a + np.clip(float((x - a) @ ab) / den, 0.0, 1.0) * ab

    graph = near.graph
    ring = graph.indices[graph.indptr[c]:graph.indptr[c + 1]]
    if not len(ring):
        return None
    u = v[ring].mean(0) - v[c]
    if np.linalg.norm(u) <= 0:
        return None
    u = u / np.linalg.norm(u)
    p = v[c].copy()
    path = [p]
    frac = (np.arange(LINE_SAMPLES) + 0.5) / LINE_SAMPLES
    vf = _vertex_faces(body, near)
    for _ in range(MAX_STEPS):
        x = p + step * u
        reach = float(np.linalg.norm(x - on_bone(x)))
        sel = np.asarray(near.kd.query_ball_point(x, reach), np.int64)
        if len(sel) < 3:
            return None
        faces = body.f[np.unique(vf[sel].indices)]
        cut = _section(v, faces, x, u)
        if cut is None or not cut[1] or cut[2] > reach:
            return None  # no section, or one wider than the reach: not this branch's
        m = cut[0]
        if body.inner_radius(m[None])[0] <= 0:
            return None  # the centroid is outside the mesh: not a limb's section
        d = m - p
        if np.linalg.norm(d) <= 1e-9 * body.size:
            return None
        u, p = d / np.linalg.norm(d), m
        path.append(p)
        q = on_bone(p)
        if (body.inner_radius(p + frac[:, None] * (q - p)) > 0).all():
            path.append(q)
            return np.array(path)
    return None


def simplify(path: np.ndarray, tol: float) -> np.ndarray:
    """Indices of the points of the polyline ``path`` (K,3) that Douglas-Peucker keeps at
    tolerance ``tol`` mm (the first and last always)."""
    keep = np.zeros(len(path), bool)
    keep[[0, -1]] = True
    stack = [(0, len(path) - 1)]
    while stack:
        i, j = stack.pop()
        if j <= i + 1:
            continue
        seg = path[j] - path[i]
        n2 = float(seg @ seg)
        rel = path[i + 1:j] - path[i]
        t = np.clip(rel @ seg / n2, 0.0, 1.0) if n2 > 0 else np.zeros(len(rel))
        dist = np.linalg.norm(rel - t[:, None] * seg, axis=1)
        k = int(np.argmax(dist))
        if dist[k] > tol:
            keep[i + 1 + k] = True
            stack += [(i, i + 1 + k), (i + 1 + k, j)]
    return np.flatnonzero(keep)


def resample(path: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Points (N,3) at arc lengths ``s`` (N,) mm along the polyline ``path`` (K,3)."""
    seg = np.linalg.norm(np.diff(path, axis=0), axis=1)
    cum = np.r_[0.0, np.cumsum(seg)]
    return np.column_stack([np.interp(s, cum, path[:, k]) for k in range(3)])
