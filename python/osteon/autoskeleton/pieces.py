"""Step 0b: a mesh in several pieces (units: mm).

Most character models are several pieces: eyes and teeth inside the head, a beak or a hat
overlapping it, sometimes a loose prop. The main body is the piece enclosing the largest
volume; a piece is joined to the body when it touches or overlaps a piece already joined (some
vertex of one lies inside the other or within ``TOUCH`` × the smaller piece's size of its
surface), repeatedly; the rest are loose pieces, in the sense of the analysis's
``loose_pieces``: nothing holds them to the body, so they would fall off the print."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .mesh import piece_labels

#: two pieces touch when a vertex of one is within TOUCH x the smaller piece's size (largest
#: bounding-box side) of the other's surface, or inside it
TOUCH = 0.02


@dataclass
class Pieces:
    """The pieces of a welded mesh.

    labels (V,) int: piece of each vertex (-1: in no face); main: the body's label; joined:
    labels of pieces touching the body (directly or through another joined piece); loose:
    labels of the others; volume (P,) mm³, size (P,) mm, closed (P,) bool: per label."""

    labels: np.ndarray
    main: int
    joined: list[int]
    loose: list[int]
    volume: np.ndarray
    size: np.ndarray
    closed: np.ndarray

    def vertices_of(self, labels: list[int]) -> np.ndarray:
        """Indices of the vertices in the pieces ``labels``."""
        return np.flatnonzero(np.isin(self.labels, labels))


def _piece_measures(v: np.ndarray, f: np.ndarray, labels: np.ndarray, n: int):
    """Per piece: enclosed volume (mm³, 0 if open), bounding box low and high corners (n,3) mm,
    closed (every edge in 2 faces)."""
    fl = labels[f[:, 0]]
    signed = np.einsum("ij,ij->i", v[f[:, 0]], np.cross(v[f[:, 1]], v[f[:, 2]])) / 6.0
    volume = np.abs(np.bincount(fl, signed, minlength=n))
    edges = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    uniq, counts = np.unique(edges, axis=0, return_counts=True)
    closed = np.bincount(labels[uniq[counts != 2, 0]], minlength=n) == 0
    lo, hi = np.full((n, 3), np.inf), np.full((n, 3), -np.inf)
    inside = labels >= 0
    np.minimum.at(lo, labels[inside], v[inside])
    np.maximum.at(hi, labels[inside], v[inside])
    return np.where(closed, volume, 0.0), lo, hi, closed


def _distance_field(v: np.ndarray, f: np.ndarray, closed: bool):
    """(pygel3d ``MeshDistance`` of the triangles ``f`` (signed distance mm, < 0 inside),
    whether its inside means anything): an open piece whose holes :func:`cap_holes` closes is
    measured capped, so a limb plugged into its holes lies inside it.

    Why: low-poly figures are often open shells plugged into one another (issue 35: RigNet
    9477's legs are open tubes whose tops reach 9 mm up into the open bottom of its open torso;
    no leg vertex is near the torso's surface, so the legs were loose and got no bones)."""
    from pygel3d import hmesh

    used, inv = np.unique(f, return_inverse=True)
    pv, pf = v[used], inv.reshape(f.shape).astype(np.int32)
    capped = None if closed else cap_holes(pv, pf)
    if capped is not None:
        pv, pf = capped
    return hmesh.MeshDistance(hmesh.Manifold.from_triangles(pv, pf)), closed or capped is not None


def _touch(v, f, labels, closed, size, a: int, b: int, fields: dict) -> bool:
    """Whether pieces ``a`` and ``b`` touch or overlap (a vertex of one inside the other,
    capped if open, or near its surface)."""
    tol = TOUCH * min(size[a], size[b])
    for p, q in ((a, b), (b, a)):
        if p not in fields:
            fields[p] = _distance_field(v, f[labels[f[:, 0]] == p], bool(closed[p]))
        field, solid = fields[p]
        d = np.asarray(field.signed_distance(v[labels == q]), dtype=np.float64)
        if (np.abs(d) <= tol).any() or (solid and (d < 0).any()):
            return True
    return False


def split_pieces(v: np.ndarray, f: np.ndarray) -> Pieces:
    """The main body, the pieces joined to it and the loose pieces of the welded mesh
    ``v`` (V,3) mm, ``f`` (F,3)."""
    n, labels = piece_labels(f, len(v))
    in_face = np.zeros(len(v), bool)
    in_face[f.ravel()] = True
    # relabel pieces that hold a face 0..n-1 (vertices in no face: -1)
    _, dense = np.unique(labels[in_face], return_inverse=True)
    lab = np.full(len(v), -1, np.int64)
    lab[in_face] = dense.ravel()
    volume, lo, hi, closed = _piece_measures(v, f, lab, n)
    size = (hi - lo).max(1)
    main = int(np.argmax(np.where(volume > 0, volume, -1.0 / (1.0 + size))))
    held, todo, fields = [main], [main], {}
    rest = np.array([k for k in range(n) if k != main], np.int64)
    while todo and len(rest):
        a = todo.pop()
        tol = TOUCH * np.minimum(size[a], size[rest])[:, None]
        boxes = np.all((lo[a] - tol <= hi[rest]) & (lo[rest] - tol <= hi[a]), axis=1)
        near = [int(b) for b in rest[boxes]
                if _touch(v, f, lab, closed, size, a, int(b), fields)]
        rest = rest[~np.isin(rest, near)]
        held += near
        todo += near
    return Pieces(lab, main, sorted(held[1:]), sorted(int(k) for k in rest), volume, size,
                  closed)


def _boundary_loops(f: np.ndarray) -> list[list[int]] | None:
    """The boundary loops of the triangles ``f`` (F,3), each in the direction opposite to its
    faces' edges (so a fan on it faces the same way as most of them); None unless every
    boundary vertex is on exactly two boundary edges and no edge is in more than 2 faces."""
    half = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]).astype(np.int64)
    und = np.sort(half, axis=1)
    _, inv, counts = np.unique(und, axis=0, return_inverse=True, return_counts=True)
    if (counts > 2).any():
        return None
    border = half[counts[inv.ravel()] == 1]  # (a, b) as the single face holding it runs
    nbr: dict[int, list[int]] = {}
    for a, b in border:
        nbr.setdefault(int(a), []).append(int(b))
        nbr.setdefault(int(b), []).append(int(a))
    if any(len(n) != 2 for n in nbr.values()):
        return None
    along = {(int(a), int(b)) for a, b in border}
    loops = []
    while nbr:
        loop = [min(nbr)]
        prev = -1
        while True:
            n = nbr.pop(loop[-1])
            w = n[0] if n[0] != prev else n[1]
            if w == loop[0]:
                break
            prev = loop[-1]
            loop.append(w)
        pairs = list(zip(loop, loop[1:] + loop[:1], strict=True))
        if sum(p in along for p in pairs) * 2 > len(pairs):
            loop = loop[::-1]  # the faces run along the loop: the cap runs against them
        loops.append(loop)
    return loops


def orient_faces(f: np.ndarray) -> np.ndarray:
    """The connected triangles ``f`` (F,3) with each face turned, if need be, to run every
    shared edge opposite to its neighbour's (breadth first from face 0): a few flipped faces in
    an open low-poly piece (issue 35) would otherwise split its vertices in pygel3d."""
    f = f.copy()
    half = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]).astype(np.int64)
    face_of = np.tile(np.arange(len(f)), 3)
    _, inv = np.unique(np.sort(half, axis=1), axis=0, return_inverse=True)
    inv = inv.ravel()
    sharing: dict[int, list[int]] = {}
    for h, e in enumerate(inv):
        sharing.setdefault(int(e), []).append(h)
    flipped = np.zeros(len(f), bool)
    seen = np.zeros(len(f), bool)
    seen[0] = True
    queue = [0]
    while queue:
        a = queue.pop()
        for k in range(3):
            h = a + k * len(f)
            for g in sharing[int(inv[h])]:
                b = int(face_of[g])
                if seen[b]:
                    continue
                seen[b] = True
                same = bool((half[h] == half[g]).all())  # same direction before any flips
                flipped[b] = flipped[a] ^ same
                queue.append(b)
    f[flipped] = f[flipped][:, ::-1]
    return f


def cap_holes(v: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The open piece ``v`` (V,3) mm, ``f`` (F,3) with every hole closed by a fan of triangles
    from a new vertex at the centroid of its boundary loop (appended after ``v``, so the first V
    vertices are unchanged); None if the boundary is not a set of simple loops, or if the
    capped piece encloses less than ``1e-3`` x its size³ (a sheet, not a limb: a tube of that
    volume is under 1/56 of its length across, thinner than any printable limb of a model).

    Why: low-poly models often have a limb modelled as an open tube glued onto the body
    (issue 35: the arms and legs of a 372-face figure); capped, it encloses the limb's volume
    and can be skeletonised like any closed piece."""
    f = orient_faces(f)
    loops = _boundary_loops(f)
    if loops is None or any(len(lp) < 3 for lp in loops):
        return None
    verts, faces = [v], [f]
    for n, loop in enumerate(loops, start=len(v)):
        verts.append(v[loop].mean(0)[None])
        faces.append(np.column_stack([loop, np.roll(loop, -1), np.full(len(loop), n)]))
    cv, cf = np.concatenate(verts), np.concatenate(faces).astype(f.dtype)
    volume = np.einsum("ij,ij->", cv[cf[:, 0]], np.cross(cv[cf[:, 1]], cv[cf[:, 2]])) / 6.0
    if abs(volume) < 1e-3 * float(np.ptp(cv, axis=0).max()) ** 3:
        return None
    return cv, (cf if volume > 0 else cf[:, ::-1].copy())  # outward, like the rest of the mesh
