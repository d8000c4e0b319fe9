"""The extremities of a mesh, found from its geometry alone (no rig, no osteon skeleton rule):
the second measure of ``bench_autoskeleton.py --pieces`` (issue 35: "a bone ends within 1.5
limb radii of every fingertip/extremity"). Units: mm.

Definition (fixed before any model was scored with it):

1. The solid: the main body and the pieces joined to it (``osteon.autoskeleton.split_pieces``;
   loose pieces are left out: they are reported, not rigged), each voxelised by ray parity on
   a grid of ``VOXELS`` cells across the model's largest side (an open piece capped first with
   ``pieces.cap_holes``; one whose holes are not simple loops by the vote of the parities along
   x, y and z, 2 of 3: Nooruddin & Turk, IEEE TVCG 2003), and their union taken, so a horn glued into a head is one solid with it and an eye inside the head adds
   nothing.
2. The core: the voxel of the main body nearest its centre of mass (the mean of its voxel
   centres; of the whole solid's if the main body is an open sheet). g: the geodesic distance from the core inside the solid (Dijkstra over the
   26-neighbour voxel graph, steps h, h√2, h√3).
3. The level sets of g in bands 2 h wide, each connected part of a band a node (a discrete
   Reeb graph: Hilaga et al., SIGGRAPH 2001), with its highest g and its radius (the largest
   distance to the outside among its voxels: the limb's radius at that level).
4. Maxima of g and their persistence (0-dimensional persistence of the superlevel sets of g
   over the node graph, elder rule: Edelsbrunner, Letscher & Zomorodian 2002): a maximum's
   persistence P is how far g falls from it before its region meets the region of a higher
   maximum; its region is the nodes it held until then. The highest maximum's region is the
   whole solid and its P the full height of g above the core.
5. An extremity is a maximum that sticks out more than its own width: P > 2 × the largest
   radius of its region (a hemispherical bump of radius a has P ≈ a and width 2a: not one; a
   finger, a leg, a horn, an ear, a tail are), and by at least ``MIN_VOXELS`` voxels (shorter
   is below the grid's resolution). Its tip is the voxel where g peaks; its limb radius r is
   the limb's radius near its end: the largest depth (distance to the outside) of the voxels
   within a distance s of the tip, for the smallest s that is 3 times that depth (a limb's
   last 3 radii: on a round end of radius r, r), s at most half of P.

The bench then scores the distance from each tip to the nearest auto bone end in units of r
(within 1.5 r: the issue's bar; the auto bones stop 1.25 r inside a round end).

The issue's definition (issue 35's Build: "branches as thin as fingers get bones when they
are longer than they are wide"; fixed and committed before any model was scored with it,
session 11): step 5 measures a branch's width by its thickness (twice its largest depth),
so the corner of a wide flat end (a paddle hand, a wing's tip, a flat foot's outer toe),
thin but not narrow, counts as a branch longer than it is wide. Here "wide" is what the word
says, the largest extent across the branch:

5'. A node's width is the larger of twice its largest depth and its extent across g: the
   largest distance between two of its voxels after projecting them on the plane
   perpendicular to g's direction there (the least-squares gradient of g over the node's
   voxels), found by a double sweep (the voxel farthest from the centroid, then the one
   farthest from it), centre to centre (h less than the part's extent: for a round limb
   twice the depth, which is h/2 more than the limb's radius, is the larger, so a round
   limb's width and radius stay those of step 5; across a flat limb the extent is the
   limb's breadth). A maximum is an extremity under the issue's definition when some stretch
   from its tip is longer than it is wide: for some level l between its peak and its death
   (step 4), the part of the solid joined to the tip above l (its superlevel component: the
   branch cut off where g = l) is more than its own width long, top - l > the largest width
   of its nodes, and at least ``MIN_VOXELS`` voxels long. Where the branch leaves a wider
   part the component takes in that part's width and the test stops passing; a finger
   passes above its base, a corner of a wide flat end (a paddle hand) never does (cut off
   where it is as long as the end is wide, the component is as wide as the end), and a limb
   ending in a paddle passes once the cut reaches the limb (its tip: the paddle's farthest
   point). Its limb radius is measured as in step 5 with each voxel's depth replaced by the
   larger of its depth and half its node's extent across (a round end: r as before; a flat
   end: half its breadth, the radius the issue's "limb radii" means for a flat limb: a bone
   at the middle of a paddle's end is within 1.5 r of its corners).

``Extremities.issue`` holds the extremities by 5' (width: the largest node width of the
region at its death); ``tips``/``radius`` step 5's (the old count, kept beside it).

6. The yardstick's precision at thin tips (session 11, issue 35; a fix of the measure, not a
   change of either definition: which maxima are extremities is decided on the voxels as
   above). The voxel depth of a limb one or two voxels in radius is known to a voxel at best
   (the depth is a distance between voxel centres: a one-voxel line reads h whatever its
   true radius under h), and the tip is a voxel centre, up to ~h inside the surface or, at a
   point thinner than a voxel, short of it. So an extremity whose radius (step 5, or 5' when
   it is the depth's and not the width across that sets it) is at most ``THIN_VOXELS`` voxels
   is measured again on the mesh itself: its tip is the mesh vertex farthest along g near
   the voxel tip (g carried onto the vertices within ``3 r + 2 h`` of it by the shortest
   straight step from an inside voxel: g(u) + |x - u|, the vertex joined to the voxel tip by
   a straight segment inside the mesh, from the deepest point within h of the voxel tip where
   that lies outside), and its radius is step 5's, with the voxels replaced by the points of a
   grid of spacing h / ``FINE`` inside the mesh and the depth by the distance to the mesh's
   surface (``inner_radius_of``; exact, not a distance between voxel centres), stopping from 3
   grid steps out. At a point sharper than a cone of half-angle asin(1/3) = 19.5 deg the depth
   within s of the tip stays under s/3 for every s: step 5's radius has no positive value
   there and this reads about the depth 3 grid steps in (0.01-0.15 mm on the RigNet models),
   so no point within 1.5 r of such a tip prints and it leaves the printable count. The voxel
   values are kept in ``tips_voxel``/``radius_voxel``."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage, sparse
from scipy.sparse import csgraph

#: voxels across the model's largest side (0.75 mm on a 120 mm model)
VOXELS = 160
#: level-set band width in voxels (wider than a diagonal step, so no step skips a band)
BAND = 2.0
#: an extremity sticks out by at least this many voxels
MIN_VOXELS = 4
#: step 6: extremities at most this many voxels in radius are measured again on the mesh
#: (at two voxels the voxel depth's error, up to h/2 or more, is a quarter of r or more)
THIN_VOXELS = 2.0
#: step 6: the mesh measure's grid spacing is h / FINE (the largest depth in a ball is then
#: missed by at most sqrt(3)/2 h / FINE: 0.11 mm at h = 0.75 mm)
FINE = 6


@dataclass
class Extremities:
    """tips (E,3) mm, radius (E,) mm, persistence (E,) mm, width (E,) mm (2 x its region's
    largest radius); h mm: the voxel size; issue: the extremities by the issue's definition
    (step 5'), their radius by 5', their width the largest width across (5') of the stretch
    that passed."""

    tips: np.ndarray
    radius: np.ndarray
    persistence: np.ndarray
    width: np.ndarray
    h: float
    issue: Extremities | None = None
    tips_voxel: np.ndarray | None = None
    radius_voxel: np.ndarray | None = None


def voxelise(pv: np.ndarray, pf: np.ndarray, origin: np.ndarray, h: float,
             shape: tuple[int, int, int]) -> np.ndarray:
    """(nx,ny,nz) bool: voxel centres inside the closed triangles ``pv``, ``pf`` (ray parity
    along z; the columns are offset by a fraction of h so that no ray runs through an edge)."""
    jit = np.array([0.1234567, 0.3456789]) * h
    tri = pv[pf]  # (F,3,3)
    xy = tri[:, :, :2] - origin[:2] - jit
    lo = np.ceil(xy.min(1) / h - 0.5).astype(np.int64)
    hi = np.floor(xy.max(1) / h - 0.5).astype(np.int64)
    lo = np.maximum(lo, 0)
    hi = np.minimum(hi, np.array(shape[:2]) - 1)
    span = np.maximum(hi - lo + 1, 0)
    count = span[:, 0] * span[:, 1]
    t = np.repeat(np.arange(len(pf)), count)
    k = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
    i = lo[t, 0] + k // np.maximum(span[t, 1], 1)
    j = lo[t, 1] + k % np.maximum(span[t, 1], 1)
    px, py = (i + 0.5) * h, (j + 0.5) * h
    a, b, c = xy[t, 0], xy[t, 1], xy[t, 2]

    def edge(p, q):
        return (q[:, 0] - p[:, 0]) * (py - p[:, 1]) - (q[:, 1] - p[:, 1]) * (px - p[:, 0])

    w0, w1, w2 = edge(b, c), edge(c, a), edge(a, b)
    area = w0 + w1 + w2
    ok = (area != 0) & (((w0 >= 0) & (w1 >= 0) & (w2 >= 0)) | ((w0 <= 0) & (w1 <= 0) & (w2 <= 0)))
    z = (w0 * tri[t, 0, 2] + w1 * tri[t, 1, 2] + w2 * tri[t, 2, 2])[ok] / area[ok]
    kz = np.clip(np.ceil((z - origin[2]) / h - 0.5).astype(np.int64), 0, shape[2])
    toggle = np.zeros((shape[0], shape[1], shape[2] + 1), np.uint8)
    np.add.at(toggle, (i[ok], j[ok], kz), 1)
    return (np.cumsum(toggle, axis=2, dtype=np.uint8)[:, :, : shape[2]] & 1).astype(bool)


def _voted(pv: np.ndarray, pf: np.ndarray, origin: np.ndarray, h: float,
           shape: tuple[int, int, int]) -> np.ndarray:
    """The voxels inside an open piece whose holes are not simple loops: inside by the ray
    parities along x, y and z, 2 of 3 (rays through a hole vote wrong on one axis)."""
    votes = sum(np.transpose(voxelise(pv[:, axes], pf, origin[axes], h,
                                      tuple(shape[a] for a in axes)).astype(np.uint8),
                             np.argsort(axes))
                for axes in ([1, 2, 0], [2, 0, 1], [0, 1, 2]))
    return votes >= 2


def _solid(v: np.ndarray, f: np.ndarray, pieces, h: float
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(union of the main and joined pieces' voxels, the main piece's voxels, grid origin)."""
    from osteon.autoskeleton.assemble import submesh
    from osteon.autoskeleton.pieces import cap_holes

    keep = pieces.vertices_of([pieces.main, *pieces.joined])
    origin = v[keep].min(0) - 2 * h
    shape = tuple(int(s) for s in np.ceil((v[keep].max(0) + 2 * h - origin) / h))
    union = np.zeros(shape, bool)
    main = None
    for k in [pieces.main, *pieces.joined]:
        pv, pf = submesh(v, f, pieces.vertices_of([k]))
        capped = None if pieces.closed[k] else cap_holes(pv, pf)
        if pieces.closed[k] or capped is not None:
            vox = voxelise(*(capped or (pv, pf)), origin, h, shape)
        else:  # holes that are not simple loops: rays through them vote wrong, 1 axis of 3
            vox = _voted(pv, pf, origin, h, shape)
        union |= vox
        if k == pieces.main:
            main = vox
    return union, main, origin


def _voxel_graph(inside: np.ndarray, h: float) -> tuple[sparse.csr_matrix, np.ndarray]:
    """(adjacency of the inside voxels over their 26 neighbours, lengths mm; flat index ->
    node index (-1 outside))."""
    index = np.full(inside.shape, -1, np.int64)
    index[inside] = np.arange(int(inside.sum()))
    rows, cols, lens = [], [], []
    nx, ny, nz = inside.shape
    for dx, dy, dz in [(a, b, c) for a in (-1, 0, 1) for b in (-1, 0, 1) for c in (-1, 0, 1)
                       if (a, b, c) > (0, 0, 0)]:
        src = index[max(0, -dx): nx - max(0, dx), max(0, -dy): ny - max(0, dy),
                    max(0, -dz): nz - max(0, dz)]
        dst = index[max(0, dx): nx + min(0, dx) or None, max(0, dy): ny + min(0, dy) or None,
                    max(0, dz): nz + min(0, dz) or None]
        both = (src >= 0) & (dst >= 0)
        rows.append(src[both])
        cols.append(dst[both])
        lens.append(np.full(int(both.sum()), h * np.sqrt(dx * dx + dy * dy + dz * dz)))
    r, c, w = np.concatenate(rows), np.concatenate(cols), np.concatenate(lens)
    n = int(inside.sum())
    adj = sparse.coo_matrix((np.r_[w, w], (np.r_[r, c], np.r_[c, r])), shape=(n, n)).tocsr()
    return adj, index


def _node_widths(pos: np.ndarray, g: np.ndarray, nid: np.ndarray, nn: int, h: float
                 ) -> np.ndarray:
    """(nn,) mm: each node's extent across g (step 5'): its voxels ``pos`` (n,3) with node
    ids ``nid`` (n,) (-1: none) projected on the plane perpendicular to the least-squares
    gradient of ``g`` over the node, the largest distance between two of them by a double
    sweep (centre to centre)."""
    ok = nid >= 0
    p, gv, k = pos[ok], g[ok], nid[ok]
    cnt = np.bincount(k, minlength=nn).astype(np.float64)
    cen = np.stack([np.bincount(k, p[:, i], nn) for i in range(3)], 1) / np.maximum(cnt, 1)[:, None]
    rel = p - cen[k]
    gm = np.bincount(k, gv, nn) / np.maximum(cnt, 1)
    dg = gv - gm[k]
    cov = np.zeros((nn, 3, 3))
    for i in range(3):
        for j in range(i, 3):
            cov[:, i, j] = cov[:, j, i] = np.bincount(k, rel[:, i] * rel[:, j], nn)
    rhs = np.stack([np.bincount(k, rel[:, i] * dg, nn) for i in range(3)], 1)
    # ridge of h^2/4 per voxel: a node one voxel thick along g has no spread to fit there
    grad = np.linalg.solve(cov + (0.25 * h * h) * cnt[:, None, None] * np.eye(3)
                           + 1e-12 * np.eye(3), rhs[:, :, None])[:, :, 0]
    norm = np.linalg.norm(grad, axis=1)
    unit = np.where(norm[:, None] > 0, grad / np.maximum(norm, 1e-300)[:, None], 0.0)
    u = unit[k]
    proj = rel - np.einsum("ij,ij->i", rel, u)[:, None] * u

    def farthest(dist: np.ndarray) -> np.ndarray:
        """(nn,) index into the voxels of each node's farthest one by ``dist`` (-1: none)."""
        order = np.lexsort((dist, k))
        last = np.r_[k[order][1:] != k[order][:-1], True]
        out = np.full(nn, -1, np.int64)
        out[k[order][last]] = order[last]
        return out

    a = farthest(np.linalg.norm(proj, axis=1))
    far = np.linalg.norm(proj - proj[a[k]], axis=1)
    out = np.zeros(nn)
    np.maximum.at(out, k, far)
    return out


def extremities(v: np.ndarray, f: np.ndarray, pieces, mesh_tips: bool = True) -> Extremities:
    """The extremities of the welded mesh ``v`` (V,3) mm, ``f`` (F,3) split into ``pieces``
    (see the module's docstring); ``mesh_tips=False``: without step 6 (the voxel figures
    before session 11)."""
    keep = pieces.vertices_of([pieces.main, *pieces.joined])
    h = float(np.ptp(v[keep], axis=0).max()) / VOXELS
    union, main, origin = _solid(v, f, pieces, h)
    depth = ndimage.distance_transform_edt(union) * h  # mm to the nearest outside voxel
    if not union.any():
        return _pack([], h, _pack([], h, None))
    cells = np.argwhere(main if main is not None and main.any() else union)
    core = tuple(cells[np.argmin(((cells - cells.mean(0)) ** 2).sum(1))])
    adj, index = _voxel_graph(union, h)
    g = csgraph.dijkstra(adj, indices=int(index[core]))
    reached = np.isfinite(g)
    pos = origin + (np.argwhere(union) + 0.5) * h  # (n,3) voxel centres, same order as index
    rad = depth[union]
    # Reeb graph: connected parts of the bands of g
    band = np.where(reached, np.floor(g / (BAND * h)), -1).astype(np.int64)
    coo = adj.tocoo()
    a, b = coo.row, coo.col
    same = (band[a] == band[b]) & reached[a]
    n = len(g)
    _count, node = csgraph.connected_components(
        sparse.coo_matrix((np.ones(int(same.sum())), (a[same], b[same])), shape=(n, n)),
        directed=False)
    node[~reached] = -1
    used, node_r = np.unique(node[reached], return_inverse=True)
    nn = len(used)
    nid = np.full(n, -1, np.int64)
    nid[reached] = node_r.ravel()
    top = np.full(nn, -np.inf)
    np.maximum.at(top, nid[reached], g[reached])
    peak = np.full(nn, -1, np.int64)  # the voxel where each node's g peaks
    order = np.flatnonzero(reached)
    at_top = order[g[order] == top[nid[order]]]
    peak[nid[at_top]] = at_top
    nrad = np.zeros(nn)
    np.maximum.at(nrad, nid[reached], rad[reached])
    across = _node_widths(pos, g, nid, nn, h)
    nwid = np.maximum(2.0 * nrad, across)  # step 5'
    half_w = np.maximum(rad, np.where(nid >= 0, 0.5 * across[np.maximum(nid, 0)], 0.0))
    cross = (nid[a] >= 0) & (nid[b] >= 0) & (nid[a] != nid[b])
    nbrs: list[list[int]] = [[] for _ in range(nn)]
    for key in np.unique(nid[a[cross]] * nn + nid[b[cross]]).tolist():
        nbrs[key // nn].append(key % nn)
    # 0-dimensional persistence of the superlevel sets of g (elder rule) by union-find
    parent = np.arange(nn)
    birth = top.copy()  # of each component (at its root)
    members: dict[int, list[int]] = {}
    done = np.zeros(nn, bool)
    out = []

    def find(x: int) -> int:
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    wmax = nwid.copy()  # each component's largest node width so far (at its root)
    passed = np.zeros(nn, bool)  # step 5': some stretch from the tip longer than its width
    out_w = []
    thin, thin_w = [], []  # (tip voxel, whether its radius is the depth's) per extremity

    def record(root: int, death: float) -> None:
        region = members[root]
        width = 2.0 * float(nrad[region].max())
        pers = float(birth[root]) - death
        tip = int(peak[root])
        if pers > width and pers >= MIN_VOXELS * h:
            out.append((pos[tip], end_radius(tip, pers / 2), pers, width))
            thin.append((tip, True))
        if passed[root]:
            rw = end_radius(tip, pers / 2, half_w)
            out_w.append((pos[tip], rw, pers, float(wmax[root])))
            thin_w.append((tip, rw == end_radius(tip, pers / 2)))  # the depth sets r_w

    def end_radius(x: int, longest: float, depth: np.ndarray = rad) -> float:
        """The largest ``depth`` (default: distance to the outside) of the voxels within s of
        voxel ``x``, for the smallest s that is 3 x that depth (s at most ``longest`` mm)."""
        d = np.linalg.norm(pos - pos[x], axis=1)
        order = np.argsort(d[d <= longest], kind="stable")
        dist, deepest = d[d <= longest][order], np.maximum.accumulate(depth[d <= longest][order])
        stop = np.flatnonzero(dist >= 3.0 * deepest)
        return float(deepest[stop[0]] if len(stop) else deepest[-1])

    for x in np.argsort(-top, kind="stable"):
        x = int(x)
        roots = {find(y) for y in nbrs[x] if done[y]}
        done[x] = True
        members[x] = [x]
        if not roots:
            continue  # a new maximum
        elder = max(roots, key=lambda r: birth[r])
        for r in roots:
            if r != elder:
                record(r, float(top[x]))
        for r in roots:
            parent[r] = elder
            if r != elder:
                members[elder] += members.pop(r)
                wmax[elder] = max(wmax[elder], wmax[r])
        parent[x] = elder
        members[elder] += members.pop(x)
        wmax[elder] = max(wmax[elder], nwid[x])
        stretch = float(birth[elder] - top[x])  # the tip's component down to this level
        if stretch > wmax[elder] and stretch >= MIN_VOXELS * h:
            passed[elder] = True
    for r in {find(x) for x in range(nn)}:  # the highest maximum: down to the core
        record(r, float(top.min()))
    if not mesh_tips:
        return _pack(out, h, _pack(out_w, h, None))
    measure = _MeshTips(v, f, pieces, h, pos, g)
    return _pack(measure(out, thin), h, _pack(measure(out_w, thin_w), h, None, out_w), out)


class _MeshTips:
    """Step 6: thin extremities' tips and radii measured on the mesh (the docstring)."""

    def __init__(self, v, f, pieces, h, pos, g):
        self.v, self.f, self.pieces, self.h, self.pos, self.g = v, f, pieces, h, pos, g
        self._inner = self._tree = self._vtree = None
        self._done: dict[tuple[int, float, float], tuple[np.ndarray, float]] = {}

    def __call__(self, out: list, thin: list) -> list:
        res = []
        for (tip, r, pers, width), (x, depth_set) in zip(out, thin, strict=True):
            if depth_set and r <= THIN_VOXELS * self.h + 1e-9:
                key = (x, r, pers)
                if key not in self._done:
                    self._done[key] = self.measure(x, r, pers)
                tip, r = self._done[key]
            res.append((tip, r, pers, width))
        return res

    def inner(self, pts: np.ndarray) -> np.ndarray:
        if self._inner is None:
            self._inner = inner_radius_of(self.v, self.f, self.pieces, self.h)
        return self._inner(pts)

    def measure(self, x: int, r: float, pers: float) -> tuple[np.ndarray, float]:
        """(tip (3,), radius) on the mesh for the extremity whose voxel tip is voxel ``x``
        (index into ``pos``), voxel radius ``r``, persistence ``pers``."""
        from scipy.spatial import cKDTree

        h, t0 = self.h, self.pos[x]
        if self._tree is None:
            ok = np.isfinite(self.g)
            self._ids = np.flatnonzero(ok)
            self._tree = cKDTree(self.pos[ok])
            self._vtree = cKDTree(self.v)
        reach = 3.0 * r + 2.0 * h
        cand = np.asarray(self._vtree.query_ball_point(t0, reach), np.int64)
        tip = t0
        if len(cand):
            c = self.v[cand]
            gx = np.full(len(c), -np.inf)
            for i, near in enumerate(self._tree.query_ball_point(c, reach + h)):
                if near:
                    u = self._ids[np.asarray(near, np.int64)]
                    gx[i] = float((self.g[u] + np.linalg.norm(self.pos[u] - c[i], axis=1)).min())
            # the segments start at the voxel tip, or where it lies outside the mesh (a
            # voxel of a point thinner than a voxel, by the z rays' parity) at the deepest
            # point within h of it (8338's tail: its voxel tip is 0.7 mm off the axis of a
            # cone 0.45 mm in radius there)
            start = t0
            if not self.inner(t0[None])[0] > 0:
                k = int(FINE)
                ax = np.arange(-k, k + 1) * (h / FINE)
                near = t0 + np.stack(np.meshgrid(ax, ax, ax, indexing="ij"), -1).reshape(-1, 3)
                near = near[np.linalg.norm(near - t0, axis=1) <= h]
                dn = self.inner(near)
                if dn.max() > 0:
                    start = near[int(np.argmax(dn))]
            steps = np.linspace(0.0, 1.0, 10)[1:-1]  # the segment's inner points
            for i in np.argsort(-gx, kind="stable"):
                if not np.isfinite(gx[i]):
                    break
                seg = start + steps[:, None] * (c[i] - start)
                if (self.inner(seg) > 0).all():
                    tip = c[i]
                    break
        # step 5's radius on a fine grid inside the mesh: the largest depth within s of the
        # tip for the smallest s that is 3 x that depth (s at most half the persistence)
        s_max = min(3.0 * (r + h), pers / 2)
        step = h / FINE
        k = int(np.ceil(s_max / step))
        axis = np.arange(-k, k + 1) * step
        grid = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), -1).reshape(-1, 3)
        d = np.linalg.norm(grid, axis=1)
        order = np.argsort(d, kind="stable")
        grid, d = grid[order][d[order] <= s_max], d[order][d[order] <= s_max]
        best, chunk = 0.0, 8192  # nearest points first, in chunks, until the stop
        for lo in range(0, len(d), chunk):
            depth = self.inner(tip + grid[lo:lo + chunk])
            dist = d[lo:lo + chunk]
            deepest = np.maximum(np.maximum.accumulate(depth), best)
            best = float(deepest[-1])
            # from 3 grid steps out: nearer, the few grid points miss the deepest point by
            # as much as its depth (the measure's floor: r >= about step, 0.125 mm at h =
            # 0.75); only inside points count
            stop = np.flatnonzero((depth > 0) & (dist >= 3.0 * deepest) & (dist >= 3.0 * step))
            if len(stop):
                return tip, float(deepest[stop[0]])
        return tip, best if best > 0 else r


def _pack(out: list, h: float, issue: Extremities | None, voxel: list | None = None
          ) -> Extremities:
    if not out:
        return Extremities(np.zeros((0, 3)), np.zeros(0), np.zeros(0), np.zeros(0), h, issue,
                           np.zeros((0, 3)), np.zeros(0))
    tips, radius, pers, width = (np.array(c) for c in zip(*out, strict=True))
    vt, vr = (tips, radius) if voxel is None else (np.array([o[0] for o in voxel]),
                                                   np.array([o[1] for o in voxel]))
    return Extremities(tips, radius, pers, width, h, issue, vt, vr)

def inner_radius_of(v: np.ndarray, f: np.ndarray, pieces, h: float):
    """pts (K,3) -> (K,) mm: the inner radius of the main and joined pieces' union at the
    points (0 outside): the largest over the pieces of the point's distance to the piece's
    surface where the point is inside it. Inside a closed (or capped) piece: by the parity of
    rays cast from the point (pygel3d's ``ray_inside_test``, 3 rays), whatever the triangles'
    orientation (session 11: the sign of pygel3d's signed distance taken with the sign of the
    piece's enclosed volume, used before, read points 45-60 mm outside three of 8210's
    low-poly pieces as inside them, one whose triangles face inwards and two that cross
    themselves, 6 and 17 vertices enclosing "volumes" of 1136 and 716 mm3 in boxes of 180
    and 1200 mm3; only points in a piece's bounding box are tested); a piece
    whose holes are not simple loops has no inside by orientation, so there the distance to
    its triangles counts at the points inside its own voxel solid (the vote of step 1, at
    voxel size ``h``; counted over the union before session 11, which read a horn tip of 9000
    18 mm deep inside the open body's solid)."""
    from osteon.autoskeleton.assemble import submesh
    from osteon.autoskeleton.curve import _mesh_distance
    from osteon.autoskeleton.pieces import cap_holes

    keep = pieces.vertices_of([pieces.main, *pieces.joined])
    origin = v[keep].min(0) - 2 * h
    shape = tuple(int(s) for s in np.ceil((v[keep].max(0) + 2 * h - origin) / h))
    closed, open_ = [], []
    for k in [pieces.main, *pieces.joined]:
        pv, pf = submesh(v, f, pieces.vertices_of([k]))
        mesh = (pv, pf) if pieces.closed[k] else cap_holes(pv, pf)
        if mesh is not None:
            closed.append((_mesh_distance(*mesh), mesh[0].min(0), mesh[0].max(0)))
        else:
            open_.append((_mesh_distance(pv, pf), _voted(pv, pf, origin, h, shape)))

    def inner(pts: np.ndarray) -> np.ndarray:
        out = np.zeros(len(pts))
        for d, lo, hi in closed:
            box = np.flatnonzero(((pts >= lo) & (pts <= hi)).all(1))
            if not len(box):
                continue
            box = box[np.asarray(d.ray_inside_test(pts[box], 3)).reshape(-1) == 1]
            if len(box):
                near = np.abs(np.asarray(d.signed_distance(pts[box]), np.float64)).reshape(-1)
                out[box] = np.maximum(out[box], near)
        if open_:
            cell = np.floor((pts - origin) / h).astype(np.int64)
            ok = ((cell >= 0) & (cell < shape)).all(1)
            for d, vox in open_:
                inside = ok.copy()
                inside[ok] = vox[tuple(cell[ok].T)]
                if inside.any():
                    near = np.abs(np.asarray(d.signed_distance(pts[inside]), np.float64))
                    out[inside] = np.maximum(out[inside], near)
        return out

    return inner


def tip_printable(v: np.ndarray, f: np.ndarray, pieces, ex: Extremities, min_t: float
                  ) -> np.ndarray:
    """(E,) bool: some point within 1.5 r of each extremity's tip (where a bone end reaches
    it, the issue's bar) is printable by the auto skeleton's own measure
    (``osteon.autoskeleton.thickness.printable_within``: the local thickness at the point,
    twice its inner radius, at least ``min_t``; on the points of a 9 x 9 x 9 grid in the ball
    of radius 1.5 r) -- the test the thin step and the tip bones apply where a bone ends. An
    extremity no printable bone end can reach is counted apart, beside the full count."""
    from osteon.autoskeleton.thickness import printable_within

    inner = inner_radius_of(v, f, pieces, ex.h)
    return np.array([printable_within(inner, tip, 1.5 * r, min_t)
                     for tip, r in zip(ex.tips, ex.radius, strict=True)], bool)


def tip_thickness(v: np.ndarray, f: np.ndarray, pieces, ex: Extremities) -> np.ndarray:
    """(E,) mm: each extremity's thickness where it is measured, 2 x the largest distance to
    the surface of the main and joined pieces (the mesh itself, not the voxels: the grid's
    h is 0.75 mm on a 120 mm model, coarser than a 0.3-0.8 mm printable wall) over the points
    of a 9 x 9 x 9 grid filling the cube of half-side 3 r round its tip (its last 3 limb
    radii: where r is measured). Inside a closed (or capped) piece: the distance to its
    surface; a piece whose holes are not simple loops has no inside of its own, so there
    the distance to its triangles counts at the points inside the voxel solid (step 1). An
    extremity thinner than a material's minimum thickness cannot be printed with it: the
    second column of the bench, beside the first, never instead of it (issue 35). Replaced
    in the bench's columns by :func:`tip_printable` (session 11: one measure with the auto
    skeleton's); kept to reproduce the earlier figures."""
    inner = inner_radius_of(v, f, pieces, ex.h)
    axis = np.linspace(-1.0, 1.0, 9)
    grid = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), -1).reshape(-1, 3)
    return np.array([2.0 * float(inner(tip + 3.0 * r * grid).max())
                     for tip, r in zip(ex.tips, ex.radius, strict=True)])
