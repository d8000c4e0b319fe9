"""Step 7: thin side branches the simplified mesh lost (units: mm).

The curve skeleton is computed on a copy simplified to the detail target, where a toe, a claw
or a wing finger 1.5-3 mm thick is a few triangles or nothing, so it gets no branch (issue 35).
This step looks for such features on the full-resolution mesh, after the bones are made:

* every vertex's distance d to the bone it is bound to most (its largest weight), and the
  vertices where d is a local maximum over their mesh neighbours: points that stick out of
  their bone's limb;
* such a point c is the tip of a thin branch when the straight line from c to its bone's
  nearest point q stays inside the mesh and the part of it beyond the limb's own surface
  (length L = d - R, R: the distance from q to the surface) is longer than ``spur`` x its
  width (2 x the largest distance to the surface along that part), as for a leaf branch in
  ``prune``; it must be at least as thick as printable (``min_t``) and no bone may already
  end within its width of c;
* candidates are taken longest first, and one within the width of a longer one already
  tested (kept or not) is the same feature (neighbouring maxima of d on one toe's end or
  along one rim).

Each tip gets a bone from q (a child of the bone q lies on) to the first point in from c that
is ``END_RATIO`` radii from c and at least ``min_t`` / 2 thick, and the vertices beyond the
limb's surface that lie nearer that bone than their own go to it.
"""

from __future__ import annotations

import numpy as np
from scipy import sparse
from scipy.sparse import csgraph
from scipy.spatial import cKDTree

from .._api import Skeleton
from .ends import END_RATIO
from .thickness import local_thickness, printable
from .tree import Body

#: samples along the line from a tip to its bone
SAMPLES = 32


def _segment_points(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(N,3) the nearest points to ``p`` (N,3) on the segments ``a``-``b`` (N,3 each)."""
    ab = b - a
    den = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    t = np.clip(np.einsum("ij,ij->i", p - a, ab) / den, 0.0, 1.0)
    return a + t[:, None] * ab


def _half_edges(body: Body) -> tuple[np.ndarray, np.ndarray]:
    """(a, b) (3F,) each: the start and end vertex of every triangle side, in face order."""
    f = body.f
    return f.ravel(order="F"), f[:, [1, 2, 0]].ravel(order="F")


def _local_maxima(body: Body, d: np.ndarray) -> np.ndarray:
    """Vertex ids (used vertices) where ``d`` (V,) is at least that of every mesh neighbour."""
    a, b = _half_edges(body)
    best = np.full(len(d), -np.inf)
    np.maximum.at(best, a, d[b])
    np.maximum.at(best, b, d[a])
    return body.used[d[body.used] >= best[body.used]]


def _mesh_graph(body: Body) -> sparse.csr_matrix:
    """(V,V) adjacency of the mesh's vertices along its edges."""
    a, b = _half_edges(body)
    n = len(body.v)
    return sparse.coo_matrix((np.ones(2 * len(a)), (np.r_[a, b], np.r_[b, a])), shape=(n, n)).tocsr()


class _Neighbourhood:
    """The mesh's vertex graph and a k-d tree of its vertices, built on first use (most meshes
    have no candidate that gets as far as :func:`_finger_like`)."""

    def __init__(self, body: Body):
        self.body = body
        self._graph: sparse.csr_matrix | None = None
        self._kd: cKDTree | None = None
        self._local = np.full(len(body.v), -1, np.int64)  # vertex -> index in a selection

    @property
    def graph(self) -> sparse.csr_matrix:
        if self._graph is None:
            self._graph = _mesh_graph(self.body)
        return self._graph

    @property
    def kd(self) -> cKDTree:
        if self._kd is None:  # (unbalanced: half the build time, the same query answers)
            self._kd = cKDTree(self.body.v, balanced_tree=False, compact_nodes=False)
        return self._kd

    def component(self, sel: np.ndarray, c: int) -> np.ndarray:
        """The vertices of ``sel`` (sorted ids) joined to vertex ``c`` (in ``sel``) by mesh
        edges between vertices of ``sel``."""
        graph, local = self.graph, self._local
        local[sel] = np.arange(len(sel))
        starts, count = graph.indptr[sel], np.diff(graph.indptr)[sel]
        first = np.cumsum(count) - count
        at = np.repeat(starts - first, count) + np.arange(int(count.sum()))
        nbr = local[graph.indices[at]]
        row = np.repeat(np.arange(len(sel)), count)
        inside = nbr >= 0
        indptr = np.r_[0, np.cumsum(np.bincount(row[inside], minlength=len(sel)))]
        sub = sparse.csr_matrix((np.ones(int(inside.sum())), nbr[inside], indptr),
                                shape=(len(sel), len(sel)))
        _n, label = csgraph.connected_components(sub, directed=False)
        part = sel[label == label[local[c]]]
        local[sel] = -1
        return part


def _finger_like(body: Body, near: _Neighbourhood, c: int, out: np.ndarray, half: float,
                 spur: float) -> bool:
    """Whether the mesh around tip vertex ``c`` less than ``half`` mm in from it along the unit
    ``out`` (3,) (pointing from the bone out to the tip: the outer half of the branch) makes
    a branch longer than ``spur`` x its width: the branch's length (2 ``half``) against twice
    the largest distance from the line through ``c`` along ``out`` of the vertices there
    connected to ``c``.  A finger passes; the rim of a flat part (a palm's edge) is a wide cap
    there and does not."""
    tip = body.v[c]
    sel = np.asarray(near.kd.query_ball_point(tip, 2.0 * half + 1e-9, return_sorted=True),
                     np.int64)
    sel = sel[(body.v[sel] - tip) @ out >= -half]  # (<= 0 near the tip)
    if c not in sel:
        return False
    rel = body.v[near.component(sel, c)] - tip
    lateral = np.linalg.norm(rel - np.outer(rel @ out, out), axis=1)
    return 2.0 * half > spur * 2.0 * float(lateral.max())


def _tips(body: Body, sk: Skeleton, owner: np.ndarray, spur: float
          ) -> tuple[list[tuple[int, np.ndarray, np.ndarray, float]], np.ndarray]:
    """([(bone, head q (3,), tail (3,), width mm)] of the thin branches found, longest first;
    (V,) each vertex's distance to its bone ``owner``, mm)."""
    v = body.v
    q_all = _segment_points(v, sk.heads[owner], sk.tails[owner])
    d = np.linalg.norm(v - q_all, axis=1)
    cand = _local_maxima(body, d)
    if not len(cand):
        return [], d
    q = q_all[cand]
    big_r = body.inner_radius(q)
    stick = d[cand] - big_r
    keep = stick > body.min_t  # (a branch at least as long as the thinnest wall is wide)
    order = np.argsort(-stick[keep], kind="stable")  # longest first: a shorter tip near a
    cand, q, stick, big_r = (x[keep][order] for x in (cand, q, stick, big_r))  # longer one's
    ends = np.concatenate([sk.heads, sk.tails])  # is the same feature
    near = _Neighbourhood(body)
    kept: list[tuple[int, np.ndarray, np.ndarray, float]] = []
    dist = np.linalg.norm(q - v[cand], axis=1)
    frac = (np.arange(SAMPLES) + 0.5) / SAMPLES
    seen_tip = np.zeros((len(cand), 3))  # the tips tested so far and their widths
    seen_width = np.zeros(len(cand))
    n_seen = 0
    for c, qc, length, dc, r_q in zip(cand, q, stick, dist, big_r, strict=True):
        length = float(length)
        tip = v[c]
        if n_seen and (np.linalg.norm(seen_tip[:n_seen] - tip, axis=1)
                       <= seen_width[:n_seen]).any():
            continue  # within the width of a longer one's tip: the same feature
        u = (qc - tip) / dc
        s = frac * dc
        # Only the samples beyond the limb's surface are measured: the others lie within
        # r_q of qc, inside the ball of radius r_q round qc that is inside the mesh.
        out = s <= length + 1e-6 * body.size
        rho = np.full(SAMPLES, np.nan)
        rho[out] = body.inner_radius(tip + s[out, None] * u)
        if not (rho[out] > 0).all():
            continue  # the line leaves the mesh: not a straight branch off this bone
        rho_max = float(rho[s <= length].max()) if (s <= length).any() else 0.0
        width = float(local_thickness(rho_max))
        if not printable(rho_max, body.min_t) or length <= spur * width:
            continue  # thinner than printable, or a bump: not longer than wide
        seen_tip[n_seen], seen_width[n_seen] = tip, width
        n_seen += 1
        if np.linalg.norm(ends - tip, axis=1).min() <= width:
            continue  # a bone already ends there
        if not _finger_like(body, near, int(c), -u, 0.5 * length, spur):
            continue  # a ridge or a rim (a flat part's edge), not a branch
        tail = _tail(body, tip, u, s, rho, length)
        kept.append((int(owner[c]), qc, tail, width))
    return kept, d


def _tail(body: Body, tip: np.ndarray, u: np.ndarray, s: np.ndarray, rho: np.ndarray,
          length: float) -> np.ndarray:
    """Where a thin branch's bone ends (3,) mm: the first sample in from ``tip`` along the unit
    ``u`` (at distances ``s`` (K,) mm, ascending; inner radii ``rho`` (K,) mm, NaN where not
    measured yet: the samples inside the limb, measured here only if none before them stops)
    that is ``END_RATIO`` radii from the tip and at least ``min_t`` / 2 thick; failing that,
    half the branch's ``length`` in from the tip."""
    todo = np.isnan(rho)
    for _ in range(2):
        with np.errstate(invalid="ignore"):  # (NaN compares False)
            stop = np.flatnonzero((s >= END_RATIO * rho) & printable(rho, body.min_t))
        if len(stop) or not todo.any():
            break
        rho = rho.copy()
        rho[todo] = body.inner_radius(tip + s[todo, None] * u)
    return tip + s[stop[0]] * u if len(stop) else tip + 0.5 * length * u


def add_thin_branches(body: Body, sk: Skeleton, full: np.ndarray, spur: float
                      ) -> tuple[Skeleton, np.ndarray]:
    """(Skeleton, (V,B') weights) with a bone for every thin branch of ``body`` that ``sk``
    (weights ``full`` (V,B)) misses; unchanged if there is none."""
    if sk.num_bones == 0 or not len(body.used):
        return sk, full
    owner = np.argmax(full, axis=1)
    tips, own_d = _tips(body, sk, owner, spur)
    if not tips:
        return sk, full
    heads, tails = list(sk.heads), list(sk.tails)
    parents, names = list(sk.parents), list(sk.names)
    new_owner = owner.copy()
    for b, qc, tail, _width in tips:
        nb = len(heads)
        heads.append(qc)
        tails.append(tail)
        parents.append(b)
        names.append(f"auto_{nb:02d}")
        axis = tail - qc
        n = float(np.linalg.norm(axis))
        idx = np.flatnonzero(owner == b)  # (only the vertices of the bone it hangs from)
        v = body.v[idx]
        beyond = ((v - qc) @ (axis / n)) > float(body.inner_radius(qc[None])[0])
        near = np.linalg.norm(v - _segment_points(v, np.broadcast_to(qc, v.shape),
                                                  np.broadcast_to(tail, v.shape)), axis=1)
        new_owner[idx[beyond & (near < own_d[idx])]] = nb
    out = np.zeros((len(full), len(heads)))
    out[:, : full.shape[1]] = full
    moved = new_owner != owner
    out[moved] = 0.0
    out[moved, new_owner[moved]] = 1.0
    return Skeleton(np.array(heads), np.array(tails), np.array(parents, np.int64), names), out
