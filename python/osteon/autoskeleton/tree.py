"""Step 2: the curve skeleton as a tree rooted at the root node (units: mm).

The skeleton graph is made a tree by a shortest-path tree from the root node (Dijkstra, edge
lengths in mm): every loop (a torus, a handle, an arm touching the hip) is cut at the point
farthest from the root along the skeleton, and its two halves become two branches."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import sparse
from scipy.sparse import csgraph
from scipy.spatial import cKDTree

from .curve import CurveSkeleton, nearest_vertices
from .mesh import used_vertices


@dataclass
class Body:
    """The welded mesh and what every step reads of it.

    v (V,3) mm, f (F,3): the welded mesh; used (U,): vertices in a face; is_used (V,) bool;
    size mm: the largest bounding-box side; up (3,) unit; spos (S,3) mm, sedges (E,2): the
    simplified mesh; near_d (V,4) mm, near_i (V,4): each vertex's nearest simplified vertices;
    surface: pygel3d ``MeshDistance`` of the full mesh; min_t mm: the thinnest printable
    wall (a limb thinner than this is not printed, so no bone reaches into it)."""

    v: np.ndarray
    f: np.ndarray
    used: np.ndarray
    is_used: np.ndarray
    size: float
    up: np.ndarray
    spos: np.ndarray
    sedges: np.ndarray
    near_d: np.ndarray
    near_i: np.ndarray
    surface: Any
    min_t: float = 0.8

    def inner_radius(self, pts: np.ndarray) -> np.ndarray:
        """(N,) distance from each point (N,3) inside the mesh to its surface, mm (0 outside)."""
        pts = np.asarray(pts, dtype=np.float64).reshape(-1, 3)
        d = np.atleast_1d(np.asarray(self.surface.signed_distance(pts), dtype=np.float64))
        return np.maximum(-d, 0.0)


def make_body(v: np.ndarray, f: np.ndarray, up: np.ndarray, cs: CurveSkeleton,
              min_t: float = 0.8) -> Body:
    """The :class:`Body` of the welded mesh ``v`` (V,3) mm, ``f`` (F,3) and its curve skeleton
    (``min_t``: the thinnest printable wall, mm)."""
    used = used_vertices(f, len(v))
    size = float(np.ptp(v[used], axis=0).max())
    near_d, near_i = cs.near if cs.near is not None else nearest_vertices(v, cs.spos)
    is_used = np.zeros(len(v), bool)
    is_used[used] = True
    return Body(v, f, used, is_used, size, up, cs.spos, cs.sedges, near_d, near_i, cs.surface,
                min_t)


@dataclass
class Tree:
    """The skeleton tree, changed in place by pruning and re-centring.

    npos (N,3) mm: node positions; nradius (N,) mm: distance to the surface (0 outside);
    parent (N,) int (-1 at the root); alive (N,) bool; owner (S,): simplified vertex -> node
    (vertices of pruned nodes move to the node that absorbed them); root (int)."""

    npos: np.ndarray
    nradius: np.ndarray
    parent: np.ndarray
    alive: np.ndarray
    owner: np.ndarray
    root: int

    def children(self) -> list[list[int]]:
        """Each node's living children (ascending)."""
        ch: list[list[int]] = [[] for _ in range(len(self.npos))]
        for i in np.flatnonzero(self.alive & (self.parent >= 0)):
            ch[self.parent[i]].append(int(i))
        return ch

    def fold(self, node: int, into: int) -> None:
        """Remove ``node``; its simplified vertices go to ``into``."""
        self.alive[node] = False
        self.owner[self.owner == node] = into


def root_node(body: Body, npos: np.ndarray, root: str | np.ndarray) -> int:
    """The skeleton node nearest the area-weighted barycentre (``root="centre"``), nearest
    the lowest vertex along ``body.up`` (``"base"``) or nearest a point (3,) mm."""
    v, f, used = body.v, body.f, body.used
    if not isinstance(root, str):
        return int(np.argmin(np.linalg.norm(npos - root, axis=1)))
    if root == "base":
        low = v[used][np.argmin(v[used] @ body.up)]
        return int(np.argmin(np.linalg.norm(npos - low, axis=1)))
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    centre = ((a + b + c) / 3 * area[:, None]).sum(0) / area.sum()
    return int(np.argmin(np.linalg.norm(npos - centre, axis=1)))


def shortest_path_parents(npos: np.ndarray, kedges: np.ndarray, root: int, size: float
                          ) -> np.ndarray:
    """(N,) parent of each node in the shortest-path tree from ``root`` (-1 at the root).
    Skeleton pieces not connected to the root (rare) are joined at their nearest node."""
    nn = len(npos)
    elen = np.linalg.norm(npos[kedges[:, 0]] - npos[kedges[:, 1]], axis=1) + 1e-9 * size
    adj = sparse.coo_matrix(
        (np.r_[elen, elen], (np.r_[kedges[:, 0], kedges[:, 1]], np.r_[kedges[:, 1], kedges[:, 0]])),
        shape=(nn, nn),
    ).tocsr()
    dist, pred = csgraph.dijkstra(adj, indices=root, return_predecessors=True)
    while not np.isfinite(dist).all():
        far = np.flatnonzero(~np.isfinite(dist))
        near = np.flatnonzero(np.isfinite(dist))
        d, j = cKDTree(npos[near]).query(npos[far])
        k = int(np.argmin(d))
        extra = sparse.coo_matrix(
            ([d[k] + 1e-9 * size] * 2, ([far[k], near[j[k]]], [near[j[k]], far[k]])),
            shape=(nn, nn),
        )
        adj = (adj + extra).tocsr()
        dist, pred = csgraph.dijkstra(adj, indices=root, return_predecessors=True)
    parent = pred.astype(np.int64)  # -9999 at the root
    parent[root] = -1
    return parent


def make_tree(body: Body, cs: CurveSkeleton, root: str | np.ndarray) -> Tree:
    """The :class:`Tree` of the curve skeleton ``cs`` (needs at least 2 nodes)."""
    nn = len(cs.npos)
    smap = cs.smap
    bad = (smap < 0) | (smap >= nn)
    if bad.any():  # simplified vertices the map left out: nearest skeleton node
        smap = smap.copy()
        smap[bad] = cKDTree(cs.npos).query(cs.spos[bad])[1]
    npos = cs.npos.copy()
    nradius = body.inner_radius(npos)  # body radius at each node (0 if the node is outside)
    r = root_node(body, npos, root)
    parent = shortest_path_parents(npos, cs.kedges, r, body.size)
    return Tree(npos, nradius, parent, np.ones(nn, bool), smap.copy(), r)
