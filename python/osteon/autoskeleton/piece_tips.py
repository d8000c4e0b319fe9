"""Step 7b: limb ends modelled as small pieces (units: mm).

A joined piece too small to get bones of its own (``assemble``: under ``BIG_PIECE`` of the
body's volume, ``LIMB_SIZE`` / ``CLOSED_LIMB_SIZE`` of the model's size) takes the weights of
the body next to it, and the thin-branch step (``thin``) never sees it: it works on one rigged
piece at a time. On low-poly figures such pieces are often the ends of limbs: RigNet 1347's
hands are three open 8-vertex boxes each (5.4 x 9 x 5.4 mm) glued under the end of its closed
arm pieces, 7.7 mm past the arm's last vertex, and the bench's extremity measure missed all six
hand ends by 4.4-8.1 limb radii (issue 35). Each such piece is tested as a thin branch would
be, on the union of the pieces:

* the piece must be a solid: closed, or its holes closed by ``pieces.cap_holes`` (a sheet is
  not a limb);
* b: the bone most of its vertices are bound to (the weights copied from the body); c: its
  vertex farthest from b; q: the nearest point of b to c;
* the straight line from c to q stays inside the union of the piece and the rigged pieces
  (inner radius > 0 at 32 samples, the inner radius of the union being the largest of the
  pieces' own: each piece is closed, so a point inside one is inside the union);
* the part of it beyond the limb's surface (length L = |c - q| - the inner radius at q) is
  longer than ``spur`` x its width (2 x the largest inner radius along that part) and that
  width is at least ``min_thickness`` (printable), as for a thin branch;
* no bone ends within that width of c;
* the piece is not a flat plate there: its vertices less than L / 2 in from c along the line
  lie within L / (2 ``spur``) of the line through their own centroid parallel to it (a
  finger's outer half; the rim of a plate is as broad as the plate);

then a bone runs from q (a child of b) to the first point in from c that is ``END_RATIO``
radii from c and printable (``thin._tail``), and the piece's vertices nearer that bone than b
go to it (weight 1)."""

from __future__ import annotations

import numpy as np

from .._api import Skeleton
from .curve import _mesh_distance
from .thickness import local_thickness, printable
from .thin import SAMPLES, _segment_points, _tail

Mesh = tuple[np.ndarray, np.ndarray]  # (vertices (n,3) mm, faces (m,3)) of a closed piece


class _Union:
    """The inner radius of the union of closed ``meshes`` and of a ``base`` union (pygel3d
    ``MeshDistance``es built on first use: most pieces fail the shape tests before any is
    needed); ``min_t`` mm: the thinnest printable wall."""

    def __init__(self, meshes: list[Mesh], min_t: float, base: _Union | None = None):
        self.meshes, self.min_t, self.base = meshes, min_t, base
        self._dist: list | None = None

    def inner_radius(self, pts: np.ndarray) -> np.ndarray:
        """(N,) distance from each point (N,3) to the union's surface, mm (0 outside): the
        largest of the pieces' own (a point inside one closed piece is inside the union)."""
        if self._dist is None:
            self._dist = [_mesh_distance(*m) for m in self.meshes]
        pts = np.asarray(pts, dtype=np.float64).reshape(-1, 3)
        r = np.zeros(len(pts))
        for m in self._dist:
            r = np.maximum(r, -np.atleast_1d(np.asarray(m.signed_distance(pts), np.float64)))
        return r if self.base is None else np.maximum(r, self.base.inner_radius(pts))


def _flat(pts: np.ndarray, c: np.ndarray, u: np.ndarray, length: float, spur: float) -> bool:
    """Whether the vertices ``pts`` (n,3) less than ``length`` / 2 in from ``c`` along the unit
    ``u`` (from c inward) spread farther than ``length`` / (2 ``spur``) from the line through
    their centroid along ``u`` (a plate's rim, not a finger's outer half)."""
    outer = pts[(pts - c) @ u <= 0.5 * length]
    rel = outer - outer.mean(0)
    lateral = np.linalg.norm(rel - np.outer(rel @ u, u), axis=1)
    return 2.0 * spur * float(lateral.max()) >= length


def _piece_tip(pts: np.ndarray, head: np.ndarray, tail: np.ndarray, union: _Union,
               ends: np.ndarray, spur: float) -> tuple[np.ndarray, np.ndarray] | None:
    """(head q (3,), tail (3,)) of the bone for the small piece of vertices ``pts`` (n,3) mm
    bound to the bone ``head``-``tail``, or None when it is no limb end (the module's tests)."""
    q_all = _segment_points(pts, np.broadcast_to(head, pts.shape), np.broadcast_to(tail, pts.shape))
    d = np.linalg.norm(pts - q_all, axis=1)
    k = int(np.argmax(d))
    c, qc, dc = pts[k], q_all[k], float(d[k])
    if dc <= union.min_t:
        return None
    u = (qc - c) / dc
    s = (np.arange(SAMPLES) + 0.5) / SAMPLES * dc
    rho = union.inner_radius(c + s[:, None] * u)
    length = dc - float(union.inner_radius(qc[None])[0])
    part = s <= length
    if length <= union.min_t or not part.any() or not (rho[part] > 0).all():
        return None  # the line leaves the pieces, or no part of it is beyond the limb
    width = float(local_thickness(rho[part].max()))
    if not printable(rho[part].max(), union.min_t) or length <= spur * width:
        return None  # thinner than printable, or a bump
    if np.linalg.norm(ends - c, axis=1).min() <= width or _flat(pts, c, u, length, spur):
        return None  # a bone already ends there, or a plate's rim
    return qc, _tail(union, c, u, s, rho, length)


def _distance_to(pts: np.ndarray, head: np.ndarray, tail: np.ndarray) -> np.ndarray:
    """(n,) distance of each point (n,3) to the segment ``head``-``tail``, mm."""
    return np.linalg.norm(pts - _segment_points(pts, np.broadcast_to(head, pts.shape),
                                                np.broadcast_to(tail, pts.shape)), axis=1)


def add_piece_tips(v: np.ndarray, sk: Skeleton, full: np.ndarray,
                   small: list[tuple[np.ndarray, Mesh]], rigged: list[Mesh], spur: float,
                   min_t: float) -> tuple[Skeleton, np.ndarray]:
    """(Skeleton, (V,B') weights) with a bone for every small piece that is a limb end.
    ``small``: (its vertices not rigged (ids into ``v``), its closed or capped mesh);
    ``rigged``: the rigged pieces' meshes; ``full`` (V,B) the weights so far."""
    heads, tails, parents = list(sk.heads), list(sk.tails), list(sk.parents)
    ends = np.concatenate([sk.heads, sk.tails])
    body = _Union(rigged, min_t)
    moves: list[tuple[np.ndarray, int]] = []
    for verts, mesh in small:
        b = int(np.bincount(np.argmax(full[verts], axis=1)).argmax())
        pts = v[verts]
        bone = _piece_tip(pts, sk.heads[b], sk.tails[b], _Union([mesh], min_t, body), ends,
                          spur)
        if bone is None:
            continue
        heads.append(bone[0])
        tails.append(bone[1])
        parents.append(b)
        ends = np.concatenate([ends, np.array(bone)])
        nearer = _distance_to(pts, *bone) < _distance_to(pts, sk.heads[b], sk.tails[b])
        moves.append((verts[nearer], len(heads) - 1))
    if not moves:
        return sk, full
    out = np.zeros((len(full), len(heads)))
    out[:, : full.shape[1]] = full
    for idx, nb in moves:
        out[idx] = 0.0
        out[idx, nb] = 1.0
    return Skeleton(np.array(heads), np.array(tails), np.array(parents, np.int64),
                    [f"auto_{i:02d}" for i in range(len(heads))]), out
