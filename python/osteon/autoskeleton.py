"""Automatic skeleton and skinning weights for unrigged closed meshes (issue 17). Units: mm.

``auto_skeleton(vertices, faces)`` computes a curve skeleton with pygel3d's multi-scale local
separators (``pygel3d.graph.MSLS_skeleton_and_map``, MIT, Bærentzen & Rotenberg) on a
quadric-simplified copy of the mesh, then turns it into a bone tree:

1. The skeleton graph is made a tree by a shortest-path tree from the root node (Dijkstra,
   edge lengths in mm): every loop (a torus, a handle, an arm touching the hip) is cut at the
   point farthest from the root along the skeleton, and its two halves become two branches.
2. Short spurs are pruned: a leaf branch whose tip (the farthest surface point beyond the leaf)
   lies less than ``spur`` × the body radius at its junction from that junction is a bump of the
   body, not a limb; a leaf node much thinner than its parent and owning fewer vertices (a
   node in a corner of a limb's end) is folded into its parent; pruning repeats until nothing
   changes.
3. Branches (paths between the root, junctions and leaves) are split into bones where they bend
   (Ramer–Douglas–Peucker, tolerance ``bend`` × the branch's radius), and every leaf bone is
   extended to the farthest surface point along its direction, so bones reach the limbs' tips.
4. Weights: each mesh vertex belongs to the bone of its skeleton node; the one-hot binding is
   smoothed by a few rounds of neighbour averaging on the simplified mesh (so vertices near a
   joint blend the bones meeting there), interpolated back to the full mesh (inverse distance,
   4 nearest simplified vertices) and stored as a SciPy CSR matrix with at most 4 bones per
   vertex, rows summing to 1.

A mesh in several pieces raises ``ValueError`` (naming the number of pieces and their sizes):
osteon holds the model at one root bone, so a loose piece has no load path; split the pieces
and call ``auto_skeleton`` on each, or join them.
"""

from __future__ import annotations

import contextlib
import itertools
import math
import os
import sys
from typing import Any

import numpy as np
from scipy import sparse
from scipy.sparse import csgraph
from scipy.spatial import cKDTree

from ._api import Skeleton, _faces, _float_rows, _min_thickness

__all__ = ["DETAIL_LEVELS", "auto_skeleton"]

#: A limb's end bone stops where the distance to the limb's end is END_RATIO x the radius there
#: (beam sections need some distance from the load; see ``limb_end`` in ``auto_skeleton``).
END_RATIO = 1.25

#: ``detail=`` names -> vertex count of the simplified mesh the skeleton is computed on.
DETAIL_LEVELS = {"coarse": 800, "medium": 1500, "fine": 3000}


def _pieces(faces: np.ndarray, num_vertices: int) -> tuple[int, np.ndarray]:
    """Connected pieces of the mesh (over face edges): (count, per-vertex label)."""
    f = faces.astype(np.int64)
    rows = np.concatenate([f[:, 0], f[:, 1], f[:, 2]])
    cols = np.concatenate([f[:, 1], f[:, 2], f[:, 0]])
    adj = sparse.coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(num_vertices,) * 2)
    _n, labels = csgraph.connected_components(adj, directed=False)
    used = np.zeros(num_vertices, bool)
    used[f.ravel()] = True
    pieces = np.unique(labels[used])
    return len(pieces), labels


def _check_mesh(vertices: Any, faces: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    v = _float_rows(vertices, "vertices")
    if len(v) < 4:
        raise ValueError(f"mesh has {len(v)} vertices; a closed mesh needs at least 4")
    f = _faces(faces, len(v))
    if len(f) < 4:
        raise ValueError(f"mesh has {len(f)} faces; a closed mesh needs at least 4")
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    size = float(np.ptp(v[np.unique(f)], axis=0).max())
    if not size > 0:
        raise ValueError("degenerate mesh: all vertices coincide (size 0 mm)")
    if not area.sum() > 1e-12 * size * size:
        raise ValueError("degenerate mesh: total face area is zero")
    pts = v[np.unique(f)]
    thickness = np.linalg.svd(pts - pts.mean(0), compute_uv=False)[-1] / math.sqrt(len(pts))
    if thickness < 1e-6 * size:
        raise ValueError("degenerate mesh: all vertices lie in one plane (flat, no volume)")
    volume = abs(np.einsum("ij,ij->i", a, np.cross(b, c)).sum()) / 6.0
    if volume < 1e-9 * size**3:
        raise ValueError(
            f"degenerate mesh: it encloses no volume ({volume:.3g} mm³ for a {size:.3g} mm "
            "model): flat or open meshes have no skeleton"
        )
    # Weld coincident vertices (STL and other triangle soups): the skeleton is computed on the
    # welded mesh, the weights are returned for the caller's vertices.
    key = np.round(v / (1e-9 * size)).astype(np.int64)
    _, first, weld = np.unique(key, axis=0, return_index=True, return_inverse=True)
    weld = weld.ravel()
    v = v[first]
    f = weld[f]
    f = f[(f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 2] != f[:, 0])].astype(np.int32)
    if len(f) < 4:
        raise ValueError(f"mesh has {len(f)} non-degenerate faces; a closed mesh needs at least 4")
    n, labels = _pieces(f, len(v))
    if n > 1:
        counts = np.bincount(labels[np.unique(f)])
        counts = np.sort(counts[counts > 0])[::-1]
        raise ValueError(
            f"mesh is in {n} separate pieces (vertices per piece: "
            f"{', '.join(str(int(c)) for c in counts[:6])}{', …' if n > 6 else ''}); "
            "auto_skeleton needs one connected piece: split them and rig each, or join them"
        )
    return v, f, weld


def _simplified_graph(v: np.ndarray, f: np.ndarray, target: int, deterministic: bool = True):
    """pygel3d skeleton of the mesh simplified to about ``target`` vertices.

    Returns (simplified vertex positions (S,3), simplified edges (E,2), skeleton node positions
    (N,3), skeleton edges (K,2), simplified vertex -> skeleton node (S,), a
    ``pygel3d.hmesh.MeshDistance`` of the full mesh (signed distance in mm, < 0 inside))."""
    try:
        from pygel3d import graph, hmesh
    except ImportError as exc:  # pragma: no cover - pygel3d is a dependency
        raise ImportError("auto_skeleton needs pygel3d (pip install pygel3d)") from exc
    used = np.unique(f)
    m = hmesh.Manifold.from_triangles(v, f)
    if len(m.positions()) < len(used):
        raise ValueError("mesh is not manifold enough to skeletonise (pygel3d dropped vertices)")
    # Distance to the full mesh's surface (GEL's MeshDistance keeps its own copy of the
    # triangles, so the simplification below does not change it).
    surface = hmesh.MeshDistance(m)
    if len(used) > target:
        hmesh.quadric_simplify(m, target / len(used))
        m.cleanup()
    g = graph.from_mesh(m)
    pos = np.array(g.positions(), dtype=np.float64)
    sedges = _graph_edges(g, len(pos))
    with _quiet_stdout():  # GEL prints progress lines to C stdout
        if deterministic:  # every vertex grows a separator: no rand(), same result each run
            skel, mapping = graph.LS_skeleton_and_map(g, sampling=False)
        else:  # GEL samples with libc rand() from several threads: differs run to run
            skel, mapping = graph.MSLS_skeleton_and_map(g)
    npos = np.array(skel.positions(), dtype=np.float64)
    kedges = _graph_edges(skel, len(npos))
    vmap = np.fromiter(mapping, dtype=np.int64, count=len(pos))
    return pos, sedges, npos, kedges, vmap, surface


@contextlib.contextmanager
def _quiet_stdout():
    """Silence the C library's stdout (file descriptor 1) for the duration."""
    try:
        sys.stdout.flush()
        saved = os.dup(1)
    except (OSError, ValueError, AttributeError):  # no real fd 1 (some embedded Pythons)
        yield
        return
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
            yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)


def _graph_edges(g, n: int) -> np.ndarray:
    """(E,2) edges of a pygel3d graph (each once, i < j)."""
    pairs = [(i, j) for i in g.nodes() for j in g.neighbors(i) if i < j]
    if not pairs:
        return np.zeros((0, 2), np.int64)
    return np.array(pairs, dtype=np.int64)


def _rdp(points: np.ndarray, tol: float) -> list[int]:
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
        vertices: (V,3) float, mm. faces: (F,3) int triangles; one closed connected piece.
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
        ValueError: bad arrays, fewer than 4 faces, a flat/open/zero-volume mesh, a mesh in
        several pieces, an unknown ``detail`` or ``root``.
    """
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
    up_v = up_v / np.linalg.norm(up_v)
    for name, val in (("spur", spur), ("bend", bend)):
        if not (isinstance(val, (int, float)) and val > 0 and math.isfinite(val)):
            raise ValueError(f"{name} must be a positive number, got {val!r}")
    min_t = _min_thickness(min_thickness)

    v, f, weld = _check_mesh(vertices, faces)
    used = np.unique(f)
    size = float(np.ptp(v[used], axis=0).max())

    if seed is not None and not isinstance(seed, (int, np.integer)):
        raise ValueError(f"seed must be an int or None, got {seed!r}")
    spos, sedges, npos, kedges, smap, surface = _simplified_graph(v, f, target, seed is not None)

    def inner_radius(pts: np.ndarray) -> np.ndarray:
        """(N,) distance from each point (N,3) inside the mesh to its surface, mm (0 outside)."""
        pts = np.asarray(pts, dtype=np.float64).reshape(-1, 3)
        d = np.atleast_1d(np.asarray(surface.signed_distance(pts), dtype=np.float64))
        return np.maximum(-d, 0.0)

    stree = cKDTree(spos)
    # The 4 nearest simplified vertices of every mesh vertex (limb ends here, weights below).
    kq = min(4, len(spos))
    near_d, near_i = stree.query(v, k=kq)
    near_d, near_i = near_d.reshape(len(v), kq), near_i.reshape(len(v), kq)
    is_used = np.zeros(len(v), bool)
    is_used[used] = True
    nn = len(npos)
    if nn < 2:  # no curve skeleton (a blob): one bone along the principal axis
        c = v[used].mean(0)
        axis = np.linalg.svd(v[used] - c, full_matrices=False)[2][0]
        t = (v[used] - c) @ axis
        sk = Skeleton([c + axis * t.min() * 0.9], [c + axis * t.max() * 0.9], [-1], ["auto_00"])
        return sk, sparse.csr_matrix(np.ones((len(weld), 1)))
    bad = (smap < 0) | (smap >= nn)
    if bad.any():  # simplified vertices the map left out: nearest skeleton node
        smap = smap.copy()
        smap[bad] = cKDTree(npos).query(spos[bad])[1]
    # Body radius at each skeleton node: distance to the surface (mm; 0 if the node is outside).
    nradius = inner_radius(npos)

    # Barycentre / base -> root node.
    if root == "base":
        low = v[used][np.argmin(v[used] @ up_v)]
        root_node = int(np.argmin(np.linalg.norm(npos - low, axis=1)))
    else:
        a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
        area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
        centre = ((a + b + c) / 3 * area[:, None]).sum(0) / area.sum()
        root_node = int(np.argmin(np.linalg.norm(npos - centre, axis=1)))

    # 1. Tree: shortest-path tree from the root (loops cut farthest from the root). Skeleton
    # pieces not connected to the root (rare) are joined at their nearest node.
    elen = np.linalg.norm(npos[kedges[:, 0]] - npos[kedges[:, 1]], axis=1) + 1e-9 * size
    adj = sparse.coo_matrix(
        (np.r_[elen, elen], (np.r_[kedges[:, 0], kedges[:, 1]], np.r_[kedges[:, 1], kedges[:, 0]])),
        shape=(nn, nn),
    ).tocsr()
    dist, pred = csgraph.dijkstra(adj, indices=root_node, return_predecessors=True)
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
        dist, pred = csgraph.dijkstra(adj, indices=root_node, return_predecessors=True)
    parent = pred.astype(np.int64)  # -9999 at the root
    parent[root_node] = -1

    # Vertex -> node for the simplified mesh (after pruning, vertices of pruned nodes move up).
    owner = smap.copy()
    alive = np.ones(nn, bool)

    def children_lists():
        ch = [[] for _ in range(nn)]
        for i in np.flatnonzero(alive & (parent >= 0)):
            ch[parent[i]].append(int(i))
        return ch

    def tip_extent(leaf: int, direction: np.ndarray) -> float:
        """How far beyond ``leaf`` along ``direction`` its surface vertices reach (mm)."""
        pts = spos[owner == leaf]
        if len(pts) == 0:
            return 0.0
        return max(0.0, float(((pts - npos[leaf]) @ direction).max()))

    def tip_point(leaf: int, direction: np.ndarray) -> np.ndarray | None:
        """The middle of the limb's end cap beyond ``leaf``: the mean of its surface vertices
        within half a radius of the farthest one along ``direction`` (mm); None if the limb
        does not reach beyond ``leaf``."""
        pts = spos[owner == leaf]
        if len(pts) == 0:
            return None
        proj = (pts - npos[leaf]) @ direction
        if proj.max() <= 0:
            return None
        margin = max(0.5 * nradius[leaf], 1e-3 * size)
        return pts[proj >= proj.max() - margin].mean(0)

    def limb_end(line: np.ndarray, leaf: int) -> tuple[np.ndarray, int]:
        """Where a limb's end bone stops (mm).  ``line`` (K,3): the branch's polyline from its
        start out to the limb's last node ``leaf``.

        Beam theory (σ = M/W) holds at a section only some way from the load (Saint-Venant): a
        section closer to the limb's end than its own radius is inside the end cap, where a
        round end's sections shrink to a sliver and F·d/W grows without bound as the cut nears
        the surface.  So the bone ends, on the limb's axis, at the first point walking in from
        the limb's end whose distance to the end is at least ``END_RATIO`` × its radius
        (distance to the surface): on a capsule just past the cap's centre (where its medial
        axis ends), on a pointed spike at its point (a cone is a slender beam to its point;
        sections thinner than printable are ``too_thin``), but never where the section is a
        sliver (under a tenth of the limb's median area).  The axis is the line fitted to the
        branch's last stretch (3 branch radii), so a last node in a corner of a blunt end
        does not bend it.

        Returns (the end point (3,), k): the bone's polyline is ``line[:k]`` then the end point
        (1 <= k <= K)."""
        n = len(line)
        # The limb's own radius: the median over its nodes outside the body's ball at the
        # branch's start (those inside it measure the body, not the limb).
        r_line = inner_radius(line)
        own = np.linalg.norm(line - line[0], axis=1) > r_line[0]
        rad = max(float(np.median(r_line[own] if own.any() else r_line)), 1e-3 * size)
        arc = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(line[::-1], axis=0), axis=1))]
        m = int(np.searchsorted(arc, 3.0 * rad)) + 1  # nodes of the last stretch, >= 2
        stretch = line[max(n - max(m, 2), 0):]
        if len(stretch) < 2:
            return line[-1], max(n - 1, 1)
        c = stretch.mean(0)
        d = np.linalg.svd(stretch - c, full_matrices=False)[2][0]
        if (stretch[-1] - stretch[0]) @ d < 0:
            d = -d
        ends = v[is_used & (owner[near_i[:, 0]] == leaf)]  # the limb's end, full mesh
        far = float((ends @ d).max()) if len(ends) else float(line[-1] @ d)
        a = c + d * ((stretch[0] - c) @ d)  # the axis point level with the stretch's start
        length = far - a @ d
        if length <= 0:
            return line[-1], max(n - 1, 1)
        t = np.linspace(length, 0.0, 400)  # from the end inwards
        pts = a + t[:, None] * d
        radius = inner_radius(pts)
        # ... and not a sliver: at least a tenth of the limb's median section area (the
        # engine's sliver rule), i.e. radius >= sqrt(0.1) x the limb's median radius.
        ok = np.flatnonzero((radius >= math.sqrt(0.1) * rad) & (length - t >= END_RATIO * radius))
        stop = pts[ok[0]] if len(ok) else a
        k = n - len(stretch) + 1  # the bone keeps the nodes before the last stretch
        return stop, max(k, 1)

    def leaf_direction(leaf: int) -> np.ndarray:
        # Direction of the last stretch of the branch (up to ~2 radii back).
        p = leaf
        back = leaf
        length = 0.0
        while parent[p] >= 0 and length < 2 * max(nradius[leaf], 1e-6):
            length += np.linalg.norm(npos[p] - npos[parent[p]])
            p = int(parent[p])
            back = p
        d = npos[leaf] - npos[back]
        n = np.linalg.norm(d)
        return d / n if n > 0 else up_v

    # 2. Prune spurs, repeatedly.
    changed = True
    while changed:
        changed = False
        ch = children_lists()
        thin: list[tuple[list[int], int]] = []
        for leaf in np.flatnonzero(alive):
            leaf = int(leaf)
            if ch[leaf] or leaf == root_node:
                continue
            par = int(parent[leaf])
            if (par >= 0 and nradius[leaf] < 0.5 * nradius[par]
                    and (owner == leaf).sum() < (owner == par).sum()):
                # A node in a corner of the limb's end (thin, few vertices): fold it into its
                # parent; the tip is still reached by the tip extension below.
                alive[leaf] = False
                owner[owner == leaf] = par
                changed = True
                break
            path = [leaf]
            while parent[path[-1]] >= 0 and len(ch[parent[path[-1]]]) == 1:
                path.append(int(parent[path[-1]]))
                if path[-1] == root_node:
                    break
            junction = int(parent[path[-1]])
            if junction < 0 or path[-1] == root_node:
                continue  # the branch reaches the root: a limb by definition
            if len(ch[junction]) < 2 and junction != root_node:
                continue
            reach = np.linalg.norm(npos[leaf] - npos[junction]) + tip_extent(
                leaf, leaf_direction(leaf)
            )
            # The branch's own width: twice the median radius of its nodes (mm).
            width = 2.0 * float(np.median(nradius[path]))
            if width < min_t:  # thinner than printable along most of its length
                thin.append((path, junction))
            elif reach - nradius[junction] < spur * width and not thin:
                # a bump: sticks out of the body by less than spur x its own width
                for p in path:
                    alive[p] = False
                    owner[owner == p] = junction
                changed = True
                break  # children lists changed
        # Limbs too thin to print get no bone: all of this round's at once (pruning one by one
        # would leave the last sibling hanging on as part of its parent's limb).
        for path, junction in thin if not changed else []:
            for p in path:
                alive[p] = False
                owner[owner == p] = junction
            changed = True

    ch = children_lists()

    # 2b. Re-centre junctions: a local-separator skeleton puts a junction node at the centroid
    # of a separator, which can sit off the limbs' axes by a limb's width or more. Move it to
    # the least-squares meeting point of the axes of the branches that meet there (each axis
    # fitted to the branch's first nodes, at least two and up to 3 junction radii out), if the
    # axes are not parallel, the point is inside the mesh and within 3 limb radii; nodes the move
    # leaves behind the junction (on the way back) are folded into it.
    def branch_nodes(j: int, first: int, upward: bool) -> list[int]:
        hi = 4.0 * max(nradius[j], 1e-3 * size)
        out, node, prev, arc = [], first, j, 0.0
        while node >= 0 and alive[node]:
            arc += float(np.linalg.norm(npos[node] - npos[prev]))
            out.append(node)
            if arc >= hi and len(out) >= 2:
                break
            if upward and node == root_node:  # the root on a limb: go on down its other side
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

    def fold(node: int, into: int) -> None:
        alive[node] = False
        owner[owner == node] = into

    for j in range(nn):
        if not alive[j] or len(ch[j]) + (parent[j] >= 0) < 3:
            continue
        branches = [(c, branch_nodes(j, c, False), False) for c in ch[j]]
        if parent[j] >= 0:
            branches.append((int(parent[j]), branch_nodes(j, int(parent[j]), True), True))
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
            continue
        x = np.linalg.solve(a_sum, b_sum)
        # the axes must really meet there: RMS distance from x to them under half a radius
        miss = math.sqrt(max(float(x @ a_sum @ x - 2 * x @ b_sum + c_sum), 0.0) / n_axes)
        if (np.linalg.norm(x - npos[j]) > 3.0 * reach or miss > 0.5 * max(nradius[j], 1e-9)
                or inner_radius(x)[0] <= 0):
            continue
        npos[j] = x
        nradius[j] = inner_radius(x)[0]
        # Fold the first nodes of each branch that now lie behind the junction.
        for (_first, nodes, upward), d in zip(branches, axes, strict=True):
            if d is None:
                continue
            for node in nodes[:-1]:
                if (npos[node] - x) @ d >= 0 or node == root_node or len(ch[node]) > 1 \
                        or (upward and parent[node] < 0):
                    break
                if upward:
                    parent[j] = parent[node]
                else:
                    for c in ch[node]:
                        parent[c] = j
                fold(node, j)
                ch = children_lists()
        ch = children_lists()

    # 3. Branches -> bones.
    heads: list[np.ndarray] = []
    tails: list[np.ndarray] = []
    parents: list[int] = []
    node_bone = np.full(nn, -1, np.int64)
    stack: list[tuple[int, int]] = [(root_node, -1)]
    root_bone = -1
    while stack:
        start, pbone = stack.pop()
        for c in ch[start]:
            path = [start, c]
            while len(ch[path[-1]]) == 1:
                path.append(ch[path[-1]][0])
            pts = npos[path].copy()
            end = path[-1]
            bpath = path  # bpath[i]: the node of pts[i] (nodes past a limb's end: none)
            if not ch[end]:  # leaf: reach the limb's end, short of its end cap
                stop, k = limb_end(pts, end)
                pts = np.vstack([pts[:k], stop])
            if start == root_node and len(ch[start]) == 1:  # the root is an end: reach it
                d = pts[0] - pts[min(2, len(pts) - 1)]
                dn = np.linalg.norm(d)
                if dn > 0:
                    stop, k = limb_end(pts[::-1], root_node)
                    bpath = [path[0], *path[len(pts) - k :]]  # bpath[0] is never assigned
                    pts = np.vstack([stop, pts[len(pts) - k :]])
            rad = float(np.median(nradius[path]))
            keep = _rdp(pts, bend * max(rad, 1e-3 * size))
            # Drop breakpoints that would make bones shorter than 1e-3 of the model.
            kept = [keep[0]]
            for k in keep[1:]:
                if np.linalg.norm(pts[k] - pts[kept[-1]]) > 1e-3 * size:
                    kept.append(k)
                elif k == keep[-1] and len(kept) > 1:
                    kept[-1] = k
            if len(kept) < 2:
                continue
            prev = pbone
            for s0, s1 in itertools.pairwise(kept):
                b = len(heads)
                heads.append(pts[s0])
                tails.append(pts[s1])
                if prev < 0 and root_bone >= 0:
                    prev = root_bone  # further branches leaving the root point hang on bone 0
                parents.append(prev)
                if root_bone < 0:
                    root_bone = b
                node_bone[bpath[s0 + 1 : s1 + 1]] = b
                prev = b
            stack.append((end, prev))
    if not heads:  # a blob: one bone along the principal axis through the barycentre
        c = v[used].mean(0)
        x = v[used] - c
        axis = np.linalg.svd(x, full_matrices=False)[2][0]
        t = x @ axis
        heads, tails, parents = [c + axis * t.min() * 0.97], [c + axis * t.max() * 0.97], [-1]
        node_bone[:] = 0
    node_bone[root_node] = max(node_bone[root_node], 0)
    # Nodes that still have no bone (pruned or skipped) take their tree parent's.
    for _ in range(nn):
        missing = np.flatnonzero(node_bone < 0)
        if not len(missing):
            break
        par = parent[missing]
        node_bone[missing] = np.where(par >= 0, node_bone[np.maximum(par, 0)], 0)
    nb = len(heads)
    skeleton = Skeleton(
        np.array(heads), np.array(tails), np.array(parents, np.int64),
        [f"auto_{i:02d}" for i in range(nb)],
    )

    # 4. Weights: one-hot on the simplified mesh, smoothed, interpolated to the full mesh.
    ns = len(spos)
    sbone = node_bone[owner]
    w = sparse.csr_matrix((np.ones(ns), (np.arange(ns), sbone)), shape=(ns, nb))
    if len(sedges):
        a = sparse.coo_matrix(
            (np.ones(2 * len(sedges)), (np.r_[sedges[:, 0], sedges[:, 1]],
                                        np.r_[sedges[:, 1], sedges[:, 0]])), shape=(ns, ns)
        ).tocsr() + sparse.identity(ns, format="csr")
        a = sparse.diags(1.0 / np.asarray(a.sum(1)).ravel()) @ a
        for _ in range(int(smooth)):
            w = a @ w
    wd = w.toarray()
    k = min(4, ns)
    d, idx = near_d, near_i
    d = d.reshape(len(v), k)
    idx = idx.reshape(len(v), k)
    inv = 1.0 / np.maximum(d, 1e-6 * size) ** 2
    full = np.einsum("vk,vkb->vb", inv, wd[idx]) / inv.sum(1, keepdims=True)
    # Keep the 4 largest weights per vertex, drop < 1 %, renormalise.
    if nb > 4:
        cut = np.partition(full, nb - 4, axis=1)[:, nb - 4 : nb - 3]
        full[full < cut] = 0.0
    full[full < np.minimum(0.01, 0.5 * full.max(1, keepdims=True))] = 0.0
    full /= full.sum(1, keepdims=True)
    return skeleton, sparse.csr_matrix(full[weld])
