"""Step 7: one skeleton for a mesh in several pieces (units: mm).

The main body and every joined piece enclosing at least ``BIG_PIECE`` × the body's volume (a
head or a limb modelled apart), every joined closed piece that is a long limb
(``CLOSED_LIMB_SIZE``) and every joined open piece at least ``LIMB_SIZE`` × the model's size
(capped) get bones of their own (a piece with an edge in 3 or 4 faces is first split into its
:func:`manifold_parts`), rooted where the piece meets the pieces rigged before it and hung from
the nearest bone there. Smaller joined pieces (eyes, teeth, a beak) take the weights of the
nearest rigged vertex; loose pieces are bound whole to their nearest bone and reported with a
:class:`LoosePiecesWarning`."""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy import sparse
from scipy.sparse import csgraph
from scipy.spatial import cKDTree

from .._api import Skeleton
from .piece_tips import add_piece_tips
from .pieces import Pieces, cap_holes

#: a joined closed piece enclosing at least BIG_PIECE x the main body's volume gets bones
BIG_PIECE = 0.1

#: so does a joined open piece (its holes capped, :func:`~.pieces.cap_holes`; it encloses no
#: volume of its own to compare) at least LIMB_SIZE x the whole model's size long (largest
#: bounding-box side): a limb modelled apart is a large share of the model's length (issue 35:
#: the arms and legs of low-poly RigNet figures are open tubes 19-37 % of the model's size, 2-4
#: % of the body's volume when capped; their eyes and teeth are under 8 % of its size)
LIMB_SIZE = 0.15

#: ... and so does a joined closed piece under BIG_PIECE x the body's volume that is a limb: at
#: least CLOSED_LIMB_SIZE x the model's size long and more than ELONGATED x as long as it is wide
#: (issue 35: the arms of RigNet 1347 are closed pieces 54 % of its size, 64 x 19 x 16 mm, 7 % of
#: its body's volume; a beak, a horn or a hat is shorter: the test creature's beak is 18 %)
CLOSED_LIMB_SIZE = 0.3
ELONGATED = 2.0

#: rig(vertices (n,3) mm, faces (m,3), root) -> (Skeleton, (n,B) dense weights)
RigOne = Callable[[np.ndarray, np.ndarray, "str | np.ndarray"], tuple[Skeleton, np.ndarray]]


class LoosePiecesWarning(UserWarning):
    """Some pieces of the mesh neither touch nor overlap the body: they have no load path."""


def submesh(v: np.ndarray, f: np.ndarray, verts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The faces of ``f`` whose vertices are all in ``verts`` (sorted indices), renumbered:
    (vertices (n,3) mm, faces (m,3) int32)."""
    keep = np.zeros(len(v), bool)
    keep[verts] = True
    sf = f[keep[f].all(1)]
    index = np.full(len(v), -1, np.int64)
    index[verts] = np.arange(len(verts))
    return v[verts], index[sf].astype(np.int32)


def elongated(pts: np.ndarray) -> bool:
    """Whether the points (n,3) mm reach more than ``ELONGATED`` x farther along their principal
    axis than across it (the second axis): a limb, not a lump."""
    c = pts.mean(0)
    extent = np.ptp((pts - c) @ np.linalg.svd(pts - c, full_matrices=False)[2][:2].T, axis=0)
    return bool(extent[0] > ELONGATED * extent[1])


def nearest_bone(sk: Skeleton, pts: np.ndarray) -> np.ndarray:
    """(P,) index of the bone (segment) nearest each point (P,3) mm."""
    d = sk.tails - sk.heads
    ll = np.maximum((d * d).sum(1), 1e-300)
    t = np.clip(np.einsum("pbk,bk->pb", pts[:, None] - sk.heads[None], d) / ll, 0.0, 1.0)
    near = sk.heads[None] + t[..., None] * d[None]
    return np.argmin(((pts[:, None] - near) ** 2).sum(2), axis=1)


def _join(parts: list[tuple[Skeleton, np.ndarray, np.ndarray]], nv: int
          ) -> tuple[Skeleton, np.ndarray]:
    """One skeleton and (nv,B) weights from the rigged pieces (skeleton, vertices, weights);
    each later piece's root bones hang from the nearest earlier bone."""
    heads, tails, parents, blocks = [], [], [], []
    for sk, verts, w in parts:
        off = sum(len(h) for h in heads)
        par = np.where(sk.parents >= 0, sk.parents + off, -1)
        if off:
            so_far = Skeleton(np.concatenate(heads), np.concatenate(tails),
                              np.concatenate(parents))
            roots = np.flatnonzero(sk.parents < 0)
            par[roots] = nearest_bone(so_far, sk.heads[roots])
        heads.append(sk.heads)
        tails.append(sk.tails)
        parents.append(par)
        blocks.append((off, verts, w))
    nb = sum(len(h) for h in heads)
    full = np.zeros((nv, nb))
    for off, verts, w in blocks:
        full[verts, off : off + w.shape[1]] = w
    sk = Skeleton(np.concatenate(heads), np.concatenate(tails), np.concatenate(parents),
                  [f"auto_{i:02d}" for i in range(nb)])
    return sk, full


def _warn_loose(pieces: Pieces, sk: Skeleton, v: np.ndarray) -> None:
    sizes = [int((pieces.labels == k).sum()) for k in pieces.loose]
    bones = [sk.names[b] for b in nearest_bone(sk, np.array(
        [v[pieces.labels == k].mean(0) for k in pieces.loose]))]
    listed = ", ".join(f"{n} vertices at {b}" for n, b in zip(sizes[:6], bones, strict=False))
    warnings.warn(LoosePiecesWarning(
        f"{len(pieces.loose)} loose piece{'s' if len(sizes) > 1 else ''} of the mesh neither "
        f"touch nor overlap the body ({listed}{', …' if len(sizes) > 6 else ''}): bound whole "
        "to the nearest bone; nothing holds them when printed (the analysis reports them as "
        "loose pieces)"), stacklevel=4)


def manifold_parts(f: np.ndarray) -> list[np.ndarray]:
    """The triangles ``f`` (F,3) of one piece grouped into parts joined through edges in exactly
    two faces: (indices into ``f``) per part.  An edge in 3 or 4 faces (two limbs modelled as
    tubes sharing an edge: issue 35, RigNet 8210's two missing limbs) separates the parts."""
    half = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    _, inv, counts = np.unique(half, axis=0, return_inverse=True, return_counts=True)
    inv = inv.ravel()
    face = np.tile(np.arange(len(f)), 3)
    two = np.flatnonzero(counts[inv] == 2)
    pairs = face[two[np.argsort(inv[two], kind="stable")]].reshape(-1, 2)
    adj = sparse.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])),
                            shape=(len(f), len(f)))
    _n, label = csgraph.connected_components(adj, directed=False)
    return [np.flatnonzero(label == c) for c in np.unique(label)]


@dataclass
class _Unit:
    """A joined piece, or a manifold part of one, as rigged: its welded vertices (sorted), mesh
    (vertices mm, faces; capped if open) or None (no simple holes), closed, volume mm³, size mm."""

    verts: np.ndarray
    mesh: tuple[np.ndarray, np.ndarray] | None
    closed: bool
    volume: float
    size: float


def _unit(v: np.ndarray, pf: np.ndarray) -> _Unit:
    """The :class:`_Unit` of the faces ``pf`` (global vertex indices) of one part."""
    verts, local = np.unique(pf, return_inverse=True)
    pv, lf = v[verts], local.reshape(pf.shape).astype(np.int32)
    edges = np.sort(np.concatenate([lf[:, [0, 1]], lf[:, [1, 2]], lf[:, [2, 0]]]), axis=1)
    closed = bool((np.unique(edges, axis=0, return_counts=True)[1] == 2).all())
    size = float(np.ptp(pv, axis=0).max())
    volume = abs(float(np.einsum("ij,ij->", pv[lf[:, 0]], np.cross(pv[lf[:, 1]], pv[lf[:, 2]]))
                       / 6.0)) if closed else 0.0
    mesh = (pv, lf) if closed else cap_holes(pv, lf)  # (small ones too: piece_tips)
    return _Unit(verts, mesh, closed, volume, size)


def _joined_units(v: np.ndarray, f: np.ndarray, pieces: Pieces) -> list[_Unit]:
    """Every joined piece as one :class:`_Unit`, or, if some edge of it is in more than two
    faces, one per :func:`manifold_parts` part."""
    units = []
    face_piece = pieces.labels[f[:, 0]]
    for k in pieces.joined:
        pf = f[face_piece == k]
        edges = np.sort(np.concatenate([pf[:, [0, 1]], pf[:, [1, 2]], pf[:, [2, 0]]]), axis=1)
        if np.unique(edges, axis=0, return_counts=True)[1].max() <= 2:
            verts = pieces.vertices_of([k])
            pv, lf = submesh(v, f, verts)
            mesh = (pv, lf) if pieces.closed[k] else cap_holes(pv, lf)
            units.append(_Unit(verts, mesh, bool(pieces.closed[k]), float(pieces.volume[k]),
                               float(pieces.size[k])))
        else:
            units += [_unit(v, pf[part]) for part in manifold_parts(pf)]
    return units


def rig_pieces(v: np.ndarray, f: np.ndarray, pieces: Pieces, root: str, rig: RigOne,
               spur: float, min_t: float) -> tuple[Skeleton, np.ndarray]:
    """Skeleton and (V,B) dense weights of the welded mesh ``v``, ``f`` in several pieces
    (``spur``, ``min_t`` mm: auto_skeleton's, as for thin branches, for the small pieces that
    are limb ends)."""
    model_size = float(np.ptp(v[pieces.labels >= 0], axis=0).max())
    limb = LIMB_SIZE * model_size
    main_verts = pieces.vertices_of([pieces.main])
    body_volume = float(pieces.volume[pieces.main])
    units = _joined_units(v, f, pieces)
    is_big = [u.mesh is not None and (
        (u.volume >= BIG_PIECE * body_volume
         or (u.size >= CLOSED_LIMB_SIZE * model_size and elongated(u.mesh[0])))
        if u.closed else u.size >= limb) for u in units]
    big = [u for u, b in zip(units, is_big, strict=True) if b]
    parts, rigged = [], np.zeros(0, np.int64)
    meshes = [(main_verts, submesh(v, f, main_verts)), *[(u.verts, u.mesh) for u in big]]
    for verts, (pv, pf) in meshes:
        at: str | np.ndarray = root
        if len(rigged):  # rooted where the piece meets the pieces rigged before it
            d, _ = cKDTree(v[rigged]).query(pv)
            at = pv[int(np.argmin(d))]
        sk, w = rig(pv, pf, at)
        own = ~np.isin(verts, rigged)  # (a vertex on an edge two parts share: the first's)
        parts.append((sk, verts[own], w[: len(verts)][own]))  # (capped: centroids dropped)
        rigged = np.concatenate([rigged, verts[own]])
    sk, full = _join(parts, len(v))
    small = np.setdiff1d(pieces.vertices_of(pieces.joined), rigged)
    if len(small):  # eyes, teeth, a beak: the weights of the body next to them
        full[small] = full[rigged[cKDTree(v[rigged]).query(v[small])[1]]]
        tips = [(np.setdiff1d(u.verts, rigged), u.mesh) for u, b in zip(units, is_big, strict=True)
                if not b and u.mesh is not None]
        sk, full = add_piece_tips(v, sk, full, [(vs, m) for vs, m in tips if len(vs)],
                                  [m for _verts, m in meshes], spur, min_t)
    for k in pieces.loose:  # a loose piece: whole to the bone nearest its centre
        verts = pieces.vertices_of([k])
        full[verts] = 0.0
        full[verts, nearest_bone(sk, v[verts].mean(0)[None])[0]] = 1.0
    free = np.flatnonzero(pieces.labels < 0)
    if len(free):  # vertices in no face: their nearest bone
        full[free] = 0.0
        full[free, nearest_bone(sk, v[free])] = 1.0
    if pieces.loose:
        _warn_loose(pieces, sk, v)
    return sk, full
