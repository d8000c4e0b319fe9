"""Step 1: simplify the mesh and compute its curve skeleton with pygel3d (units: mm).

pygel3d's local-separator skeletons (``pygel3d.graph.LS_skeleton_and_map`` /
``MSLS_skeleton_and_map``, MIT, Bærentzen & Rotenberg, "Skeletonization via local separators",
ACM TOG 2021) on a quadric-simplified copy of the mesh."""

from __future__ import annotations

import contextlib
import math
import os
import sys
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any

import numpy as np

#: edges of the simplified mesh shorter than SPACING x the local limb radius are collapsed
#: (about 2π / SPACING vertices round every limb: :func:`coarsen_by_radius`)
SPACING = 0.6

#: meshes with more faces than this are first decimated to PRE_FACES faces by the engine's quadric
#: edge collapse (:func:`predecimate`), which keeps a closed manifold closed and manifold: pygel3d's
#: simplification and distance field then work on that copy (issue 35)
PRE_DECIMATE_ABOVE = 30_000
PRE_FACES = 20_000

#: a mesh with fewer vertices than the detail target, some of whose edges are longer than
#: REFINE x SPACING x the local limb radius, is split 1 -> 4 (every edge at its midpoint) until
#: few are or the split mesh would pass half the target; :func:`coarsen_by_radius` then collapses
#: what the thick parts do not need (:func:`refine_by_radius`)
REFINE = 2.0
#: ... as long as more than LONG_SHARE of its edges are (a few corners where no ball fits, see
#: :func:`vertex_radius`, do not make the whole mesh finer)
LONG_SHARE = 0.1


@dataclass
class CurveSkeleton:
    """pygel3d's curve skeleton of the simplified mesh.

    spos (S,3) mm: simplified mesh vertices; sedges (E,2): its edges (i < j); npos (N,3) mm:
    skeleton nodes; kedges (K,2): skeleton edges; smap (S,): simplified vertex -> skeleton node
    (may hold -1 or out-of-range values, see :func:`osteon.autoskeleton.tree.fix_map`);
    surface: ``pygel3d.hmesh.MeshDistance`` of the full mesh (signed distance mm, < 0 inside);
    near: (distances (V,k) mm, ids (V,k)) of the nearest ``spos`` (k = min(4, S)) to each
    vertex of the mesh given to :func:`curve_skeleton` (``None``: not computed there)."""

    spos: np.ndarray
    sedges: np.ndarray
    npos: np.ndarray
    kedges: np.ndarray
    smap: np.ndarray
    surface: Any
    near: tuple[np.ndarray, np.ndarray] | None = None


def _mesh_distance(v: np.ndarray, f: np.ndarray):
    """pygel3d ``MeshDistance`` of the triangles ``f`` (F,3) on ``v`` (V,3) mm (its own
    ``Manifold``: the caller's copy is simplified meanwhile)."""
    from pygel3d import hmesh

    return hmesh.MeshDistance(hmesh.Manifold.from_triangles(v, f))


def nearest_vertices(v: np.ndarray, spos: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(distances (V,k) mm, ids (V,k)): the k = min(4, S) nearest of ``spos`` (S,3) mm to
    each of ``v`` (V,3) mm."""
    from scipy.spatial import cKDTree

    kq = min(4, len(spos))
    near_d, near_i = cKDTree(spos).query(v, k=kq)
    return near_d.reshape(len(v), kq), near_i.reshape(len(v), kq)


def curve_skeleton(v: np.ndarray, f: np.ndarray, target: int, deterministic: bool = True,
                   root: str | np.ndarray | None = None) -> CurveSkeleton:
    """pygel3d skeleton of the mesh (v (V,3) mm, f (F,3)) simplified to about ``target``
    vertices; ``deterministic``: every vertex grows a separator (no libc ``rand()``).  A
    low-poly piece that had to be split (:func:`refine_by_radius`) and is rooted at a point
    ``root`` (3,) mm (a piece joined to the body there) gets :func:`front_skeleton` instead."""
    try:
        from pygel3d import graph, hmesh
    except ImportError as exc:  # pragma: no cover - pygel3d is a dependency
        raise ImportError("auto_skeleton needs pygel3d (pip install pygel3d)") from exc
    full_v = v
    v, f = predecimate(v, f)
    used = np.unique(f)
    # Why two threads: pygel3d (ctypes) and SciPy's k-d tree release the GIL, so the distance
    # field is built while the copy is simplified and the full mesh's nearest simplified
    # vertices are found while the skeleton is grown, on the second core (issue 35: Make
    # skeleton's wall time); every result is the same as one after the other.
    with ThreadPoolExecutor(max_workers=1) as pool:
        # Distance to the full mesh's surface (GEL's MeshDistance keeps its own copy of the
        # triangles, so the simplification below does not change it).
        surface_job = pool.submit(_mesh_distance, v, f)
        m = hmesh.Manifold.from_triangles(v, f)
        if len(m.positions()) < len(used):
            raise ValueError("mesh is not manifold enough to skeletonise (pygel3d dropped "
                             "vertices)")
        size = float(np.ptp(v[used], axis=0).max())
        refined = False
        if len(used) > target:  # (a mesh already this small is skeletonised as it is)
            hmesh.quadric_simplify(m, target / len(used))
            m.cleanup()
            surface = surface_job.result()
            coarsen_by_radius(m, surface, size)
        else:
            surface = surface_job.result()
            if refine_by_radius(m, surface, size, target):
                coarsen_by_radius(m, surface, size, faces=True)
                refined = True
        g = graph.from_mesh(m)
        pos = np.array(g.positions(), dtype=np.float64)
        sedges = graph_edges(g, len(pos))
        if refined and root is not None and not isinstance(root, str):
            # a split low-poly piece hung from the body at ``root``: level sets from there
            start = int(np.argmin(((pos - np.asarray(root, np.float64)) ** 2).sum(1)))
            return CurveSkeleton(pos, sedges, *front_skeleton(pos, sedges, start), surface)
        near_job = pool.submit(nearest_vertices, full_v, pos)
        with quiet_stdout():  # GEL prints progress lines to C stdout
            if deterministic:  # every vertex grows a separator: no rand(), same each run
                skel, mapping = graph.LS_skeleton_and_map(g, sampling=False)
            else:  # GEL samples with libc rand() from several threads: differs run to run
                skel, mapping = graph.MSLS_skeleton_and_map(g)
        near = near_job.result()
    npos = np.array(skel.positions(), dtype=np.float64)
    kedges = graph_edges(skel, len(npos))
    vmap = np.fromiter(mapping, dtype=np.int64, count=len(pos))
    return CurveSkeleton(pos, sedges, npos, kedges, vmap, surface, near)


def front_skeleton(pos: np.ndarray, sedges: np.ndarray, start: int
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The level-set (Reeb) skeleton of the triangle mesh graph ``pos`` (S,3) mm, ``sedges``
    (E,2) of the geodesic distance from vertex ``start`` (Dijkstra along the edges): the
    vertices are cut into bands as wide as the longest edge, every connected part of a band
    (over the band's own edges) is a node at its vertices' centroid, and two nodes are joined
    where an edge crosses between them.  Returns (nodes (N,3) mm, node edges (K,2), vertex ->
    node (S,)).

    Why the longest edge: then no edge skips a band, so the triangles a level set crosses at a
    band's lower bound hold only vertices of that band and the one below, and the upper
    vertices of that strip are joined by the band's own edges: every ring of the level set is
    inside one node.  Narrower bands (twice the median edge) cut a thin limb's rings into arcs
    where its split triangles are long: a flat ribbon limb got 99 nodes and no bone to its tip.

    Why: a piece hung from the body at ``start`` (a limb modelled apart) is a tube growing away
    from there; the distance's level sets ring it, and a limb that forks splits its level sets
    (Hilaga et al., "Topology matching for fully automatic similarity estimation of 3D shapes",
    SIGGRAPH 2001; GEL's front separators, Bærentzen & Rotenberg 2021, are the same idea).  It
    costs one Dijkstra, linear in the vertices, where local separators grown from every vertex
    of a split thin piece cost 0.5-2 s CPU each (issue 35: 5.7 s on a 372-face figure)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components, dijkstra

    n = len(pos)
    a, b = sedges[:, 0], sedges[:, 1]
    length = np.linalg.norm(pos[a] - pos[b], axis=1)
    dist = dijkstra(coo_matrix((length, (a, b)), shape=(n, n)).tocsr(), directed=False,
                    indices=start)
    reached = np.isfinite(dist)
    width = float(length.max())
    level = np.full(n, -1, np.int64)  # (vertices not reached from start: one band of their own)
    level[reached] = np.floor(dist[reached] / width).astype(np.int64)
    same = level[a] == level[b]
    band = coo_matrix((np.ones(int(same.sum())), (a[same], b[same])), shape=(n, n))
    count, node = connected_components(band, directed=False)
    npos = np.zeros((count, 3))
    np.add.at(npos, node, pos)
    npos /= np.bincount(node, minlength=count)[:, None]
    kedges = np.unique(np.sort(np.column_stack([node[a[~same]], node[b[~same]]]), axis=1), axis=0)
    return npos, kedges[kedges[:, 0] != kedges[:, 1]], node


def predecimate(v: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(v, f) as they are, or, with more than ``PRE_DECIMATE_ABOVE`` faces, decimated to
    ``PRE_FACES`` faces (``osteon._core.decimate_mesh``: quadric edge collapse with the link
    condition; only vertices in a face are kept).

    Why: pygel3d's quadric simplification of the 93 k-face cow cost 0.9 s CPU and its distance
    field 0.4 s more; the engine's collapse to 20 k faces costs about 0.3 s, moves the surface by
    less than 0.05 % of the model's size there, and the rest runs on the smaller copy."""
    if len(f) <= PRE_DECIMATE_ABOVE:
        return v, f
    from .. import _core

    dv, df = _core.decimate_mesh(v, f, PRE_FACES)
    return np.asarray(dv), np.asarray(df)


def local_radius(pos: np.ndarray, normals: np.ndarray, surface, size: float) -> np.ndarray:
    """(n,) radius mm of the largest ball inside the mesh touching each surface point ``pos``
    (n,3) mm with outward unit ``normals`` (n,3), to within a factor 1.8: the deepest of the
    depths t (geometric steps from 1e-3 to 0.5 x ``size``) whose point ``pos - t normals`` is
    still at least 0.8 t deeper than ``pos`` itself (``surface``: pygel3d ``MeshDistance``).

    Depths are counted from the point's own signed distance: the points are vertices of the
    simplified copy, which sit up to ~0.002 x ``size`` off the full mesh's surface, so counted
    from the surface half of them failed the first step and kept the smallest radius (issue 35:
    on the cow the median radius was that first step and few edges were collapsed)."""
    steps = size * np.geomspace(1e-3, 0.5, 12)
    r = np.full(len(pos), steps[0])
    alive = np.arange(len(pos))
    with ThreadPoolExecutor(max_workers=1) as pool:
        offset = signed_distance(surface, pos, pool)
        for t in steps:
            d = signed_distance(surface, pos[alive] - t * normals[alive], pool)
            alive = alive[offset[alive] - d >= 0.8 * t]
            if not len(alive):
                break
            r[alive] = t
    return r


#: at least this many points are split between two threads by :func:`signed_distance`
SPLIT_POINTS = 256


def signed_distance(surface, pts: np.ndarray, pool: ThreadPoolExecutor | None = None
                    ) -> np.ndarray:
    """(n,) signed distance mm of the points ``pts`` (n,3) mm to ``surface`` (pygel3d
    ``MeshDistance``, < 0 inside); with ``pool``, the second half of many points is measured
    on its thread meanwhile (GEL's query is read-only and its ctypes call releases the GIL;
    each point's distance is the same either way)."""
    pts = np.asarray(pts, dtype=np.float64).reshape(-1, 3)
    if pool is None or len(pts) < SPLIT_POINTS:
        return np.asarray(surface.signed_distance(pts), dtype=np.float64).reshape(-1)
    half = len(pts) // 2
    second = pool.submit(surface.signed_distance, pts[half:])
    first = np.asarray(surface.signed_distance(pts[:half]), dtype=np.float64)
    return np.concatenate([first, np.asarray(second.result(), dtype=np.float64)])


def mesh_triangles(m) -> np.ndarray:
    """(F,3) vertex ids of the triangles of the pygel3d ``Manifold`` ``m``, each in its face's
    order, from one call into GEL (its OBJ writer, into a temporary file).

    Why: pygel3d hands out a face's vertices one Python call per face and one more per corner
    (``circulate_face``, ``IntVector.__getitem__``); on RigNet 8210's 12 rigged pieces these
    and the per-face and per-vertex normal calls took about half of the 0.8 s CPU spent
    measuring radii (issue 35)."""
    import tempfile

    from pygel3d import hmesh

    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "m.obj")
        hmesh.obj_save(path, m)
        with open(path) as file:
            text = "\n" + file.read()  # "v x y z" lines, then "f a b c" lines (from 1)
    start = text.find("\nf ")
    faces = text[start:] if start >= 0 else ""
    tri = np.array(faces.replace("f ", " ").split(), np.int64) - 1
    if len(tri) != 3 * faces.count("\nf "):
        raise ValueError("the simplified mesh has faces that are not triangles")
    tri = tri.reshape(-1, 3)
    if text.count("\nv ") != m.no_allocated_vertices():
        tri = np.fromiter(m.vertices(), np.int64)[tri]  # (OBJ numbers the vertices in use)
    return tri


def triangle_edges(tri: np.ndarray) -> np.ndarray:
    """(E,2) edges of the triangles ``tri`` (F,3), each once (i < j), in (i, j) order."""
    pairs = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    return np.unique(pairs, axis=0)


def unit_rows(x: np.ndarray) -> np.ndarray:
    """Rows of ``x`` (n,3) scaled to length 1 (rows of length 0 left as they are, as GEL's
    ``cond_normalize``)."""
    n = np.linalg.norm(x, axis=1, keepdims=True)
    return np.divide(x, n, out=x.copy(), where=n > 0)


def vertex_normals(pos: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """(n,3) unit normals of the vertices ``pos`` (n,3) of the triangles ``tri`` (F,3): GEL's
    ``normal(m, v)`` for all at once, the sum over a vertex's faces of the face's normal
    (from the two edges leaving the vertex, each of length 1) times its angle there."""
    out = np.zeros_like(pos)
    for k in range(3):
        v, nxt, prv = tri[:, k], tri[:, (k + 1) % 3], tri[:, (k + 2) % 3]
        e1, e0 = unit_rows(pos[nxt] - pos[v]), unit_rows(pos[prv] - pos[v])
        angle = np.arccos(np.clip(np.einsum("ij,ij->i", e0, e1), -1.0, 1.0))
        np.add.at(out, v, angle[:, None] * unit_rows(np.cross(e1, e0)))
    return unit_rows(out)


def vertex_radius(m, surface, size: float, faces: bool = True
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(positions (n,3) mm, a view of ``m``'s; the local limb radius (n,) mm at each vertex;
    the triangles (F,3), :func:`mesh_triangles`) of
    the pygel3d ``Manifold`` ``m`` (triangles): :func:`local_radius` from the vertex or, with
    ``faces``, the larger of that and the smallest from the centres of its faces.

    Why the faces: from a sharp corner (every vertex of a low-poly limb: a box's corner is 0.71 t
    deep at t along its normal) :func:`local_radius` finds no ball and returns its smallest
    step, so such a limb's edges were neither collapsed nor judged long (issue 35).  A
    quadric-simplified fine mesh has no such corners: there the faces are left out (they cost
    ~0.3 s CPU on a 20 k-face model and changed its bones)."""
    pos = m.positions()
    n = len(pos)
    tri = mesh_triangles(m)
    radius = local_radius(np.array(pos), vertex_normals(np.array(pos), tri), surface, size)
    if not faces or not len(tri):
        return pos, radius, tri
    fnormal = unit_rows(np.cross(pos[tri[:, 1]] - pos[tri[:, 0]], pos[tri[:, 2]] - pos[tri[:, 0]]))
    fradius = local_radius(pos[tri].mean(1), fnormal, surface, size)
    around = np.full(n, np.inf)
    np.minimum.at(around, tri.ravel(), np.repeat(fradius, 3))
    return pos, np.maximum(radius, np.where(np.isfinite(around), around, 0.0)), tri


def refine_by_radius(m, surface, size: float, target: int) -> int:
    """Split every triangle of ``m`` (pygel3d ``Manifold``, triangles) into 4 at its edges'
    midpoints (``hmesh.loop_split``: the surface does not move, a closed manifold stays one)
    while more than ``LONG_SHARE`` of its edges are longer than ``REFINE`` x ``SPACING`` x the
    local radius of the limb they lie on (:func:`vertex_radius`) and the split mesh would hold
    at most ``target`` / 2 vertices (the skeleton's cost grows with the vertices and with the
    length of the split triangles: splitting on to 20 000 faces cost up to 100 s CPU on a
    1 500-face model of 30 pieces, to the whole ``target`` 4 s on a 36-face leg).  Returns
    the rounds.

    Why: a local separator needs vertices round its limb; on a low-poly model (300-4 000 faces)
    a finger or a leg is a prism of 4-6 long edges, no separator rings it and the limb gets no
    branch (issue 35: a 372-face figure got one bone).  After the splits most edges are at most
    about twice ``SPACING`` x their limb's radius, and :func:`coarsen_by_radius` collapses the
    ones shorter than that on the thick parts, so about 2π / SPACING vertices ring every limb
    as on a fine mesh.  Weights stay per original vertex (interpolated from the nearest
    vertices of the skeletonised copy, :mod:`osteon.autoskeleton.weights`)."""
    from pygel3d import hmesh

    rounds = 0
    while 4 * m.no_allocated_faces() <= target:  # (split: ~2 x faces vertices, <= target / 2)
        pos, radius, tri = vertex_radius(m, surface, size)
        edges = triangle_edges(tri)  # (their order does not matter here)
        a, b = edges[:, 0], edges[:, 1]
        limit = REFINE * SPACING * np.minimum(radius[a], radius[b])
        if (np.linalg.norm(pos[a] - pos[b], axis=1) > limit).mean() <= LONG_SHARE:
            break
        hmesh.loop_split(m)
        rounds += 1
    return rounds


def coarsen_by_radius(m, surface, size: float, faces: bool = False) -> int:
    """Collapse, in the simplified mesh ``m`` (pygel3d ``Manifold``, triangles), the edges
    shorter than ``SPACING`` x the local radius of the limb they lie on, shortest (relative)
    first: a thick body keeps about 2π / SPACING vertices round it, like a thin limb.

    Why: a local separator is grown from every vertex, and each grows until it rings its
    limb, so the skeleton's cost is about (vertices) x (vertices round the thickest part); a
    quadric-simplified mesh of 1 500 vertices puts as many round a torso or a palm as the
    whole of a finger.  Evening out the vertices per limb width keeps every finger's vertices
    and divides the skeleton's cost by 2-6 (issue 35).  Returns the number collapsed.

    The edges are taken in pygel3d's graph order (each vertex's neighbours as it circulates
    them), not sorted: equal ratios (a mirror-symmetric model's two sides) are collapsed in
    that order, and sorted edges changed the bones of 6 of the 13 RigNet models in several
    pieces (9477: 17 -> 19 bones)."""
    from pygel3d import graph

    pos, radius, _tri = vertex_radius(m, surface, size, faces)  # pos: a view: collapses move it
    edges = graph_edges(graph.from_mesh(m), len(pos))
    if not len(edges):
        return 0
    a, b = edges[:, 0], edges[:, 1]
    ratio = np.linalg.norm(pos[a] - pos[b], axis=1) / (SPACING * np.minimum(radius[a], radius[b]))
    short = np.flatnonzero(ratio < 1.0)
    collapsed = 0
    for e in short[np.argsort(ratio[short], kind="stable")]:
        a, b = int(edges[e, 0]), int(edges[e, 1])
        if not (m.vertex_in_use(a) and m.vertex_in_use(b)):
            continue  # merged into a neighbour already
        d = pos[a] - pos[b]
        if math.sqrt(float(d @ d)) >= SPACING * min(radius[a], radius[b]):
            continue  # an earlier collapse moved them apart
        h = next((int(h) for h in m.circulate_vertex(a, "h") if m.incident_vertex(int(h)) == b),
                 None)
        if h is not None and m.collapse_edge(h, True):  # a goes, b stays at the midpoint
            radius[b] = min(radius[a], radius[b])
            collapsed += 1
    m.cleanup()
    return collapsed


@contextlib.contextmanager
def quiet_stdout():
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


def graph_edges(g, n: int) -> np.ndarray:
    """(E,2) edges of a pygel3d graph (each once, i < j; by node, then in the order of the
    node's neighbours) of ``n`` nodes, from one call into GEL (its graph writer, into a
    temporary file), as :func:`mesh_triangles`.

    Why: pygel3d hands out a node's neighbours one Python call per node and one more per
    neighbour; on the cow x4 the three graphs read this way cost 0.12-0.16 s CPU (issue 35)."""
    import tempfile

    from pygel3d import graph

    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "g.graph")
        graph.save(path, g)
        with open(path) as file:
            text = "\n" + file.read()  # "n x y z" lines, then "c i j" lines (i < j)
    start = text.find("\nc ")
    pairs = np.array(text[start:].replace("c ", " ").split() if start >= 0 else [], np.int64)
    if text.count("\nn ") != n or len(pairs) != 2 * text.count("\nc "):
        return _graph_edges_by_node(g)  # (a graph with nodes removed: numbered otherwise)
    pairs = pairs.reshape(-1, 2)
    if not (pairs[:, 0] < pairs[:, 1]).all():  # (another pygel3d's writer: each edge twice?)
        return _graph_edges_by_node(g)
    return pairs


def _graph_edges_by_node(g) -> np.ndarray:
    """:func:`graph_edges` one node at a time."""
    pairs = [(i, j) for i in g.nodes() for j in g.neighbors(i) if i < j]
    if not pairs:
        return np.zeros((0, 2), np.int64)
    return np.array(pairs, dtype=np.int64)
