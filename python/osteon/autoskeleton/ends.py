"""Where a limb ends: how far a leaf's surface reaches, the direction of a limb's last
stretch, and where its end bone stops (units: mm)."""

from __future__ import annotations

import math

import numpy as np

from .thickness import printable
from .tree import Body, Tree

#: A limb's end bone stops where the distance to the limb's end is END_RATIO x the radius there
#: (beam sections need some distance from the load; see :func:`limb_end`).
END_RATIO = 1.25


def tip_extent(body: Body, tree: Tree, leaf: int, direction: np.ndarray) -> float:
    """How far beyond node ``leaf`` along ``direction`` (3,) its surface vertices reach (mm)."""
    pts = body.spos[tree.owner == leaf]
    if len(pts) == 0:
        return 0.0
    return max(0.0, float(((pts - tree.npos[leaf]) @ direction).max()))


def leaf_direction(body: Body, tree: Tree, leaf: int) -> np.ndarray:
    """(3,) unit direction of the branch's last stretch into ``leaf`` (up to ~2 radii back)."""
    parent, npos = tree.parent, tree.npos
    p = leaf
    back = leaf
    length = 0.0
    while parent[p] >= 0 and length < 2 * max(tree.nradius[leaf], 1e-6):
        length += np.linalg.norm(npos[p] - npos[parent[p]])
        p = int(parent[p])
        back = p
    d = npos[leaf] - npos[back]
    n = np.linalg.norm(d)
    return d / n if n > 0 else body.up


def _end_axis(line: np.ndarray, rad: float) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """The axis fitted to the last 3 ``rad`` of the polyline ``line`` (K,3): (stretch (M,3),
    centre (3,), unit direction (3,) pointing out); None if the stretch has < 2 points."""
    n = len(line)
    arc = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(line[::-1], axis=0), axis=1))]
    m = int(np.searchsorted(arc, 3.0 * rad)) + 1  # nodes of the last stretch, >= 2
    stretch = line[max(n - max(m, 2), 0):]
    if len(stretch) < 2:
        return None
    c = stretch.mean(0)
    d = np.linalg.svd(stretch - c, full_matrices=False)[2][0]
    if (stretch[-1] - stretch[0]) @ d < 0:
        d = -d
    return stretch, c, d


def _surface_axis(ends: np.ndarray, start: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """The principal axis of a limb's own surface vertices ``ends`` (M,3) mm, for a limb that
    has a single skeleton node (a finger on a coarse simplified mesh: the line from the
    junction to that node misses the limb's axis): (its start (1,3) on the axis level with the
    limb's vertex nearest ``start``, centre (3,), unit direction (3,) pointing away from
    ``start``); None unless the limb is longer than it is wide."""
    if len(ends) < 6:
        return None
    c = ends.mean(0)
    d = np.linalg.svd(ends - c, full_matrices=False)[2][0]
    if (c - start) @ d < 0:
        d = -d
    t = (ends - c) @ d
    off = np.linalg.norm(ends - c - t[:, None] * d, axis=1)
    if np.ptp(t) <= 2.0 * float(np.median(off)):  # not longer than wide: a bump or a blob
        return None
    return (c + d * t.min())[None], c, d


def _tip(body: Body, pts: np.ndarray, radius: np.ndarray, capped: np.ndarray,
         stop: np.ndarray, i: int) -> np.ndarray | None:
    """Where a tapering limb's tip bone ends (3,) mm, or None: ``pts`` (400,3) the limb's
    axis from its end inwards, ``radius`` (400,) mm the distance to the surface there,
    ``capped`` (400,) whether the end is ``END_RATIO`` radii away; ``stop`` = ``pts[i]``: where
    the end bone stops (the sliver rule).

    The rule (issue 35): past the sliver rule's stop the axis goes on to the first point,
    walking in from the end, that is END_RATIO radii from the end and still as thick as the
    thinnest printable wall (radius >= ``body.min_t`` / 2); if that point lies further out than
    twice the radius at the stop (the tip is longer than it is wide) and the axis between
    them stays inside the mesh, a tip bone runs there.  Why: on a pointed limb (a tail, an
    ear, a horn, a claw) the sections fall under a tenth of the limb's median area a third
    of its taper short of its point, so the end bone left the tip unposed; the stop stays a
    joint (the sections up to it are the limb's; those beyond are thin, flagged by the
    analysis' own too-thin rule)."""
    ok = np.flatnonzero(printable(radius[:i], body.min_t) & capped[:i])
    if not len(ok):
        return None
    more = pts[ok[0]]
    if np.linalg.norm(more - stop) <= 2.0 * max(float(radius[i]), 1e-3 * body.size):
        return None
    s = np.linspace(0.0, 1.0, 20)[:, None]
    if not (body.inner_radius(stop + s * (more - stop)) > 0).all():
        return None
    return more


#: points of a limb's axis measured at a time, from its end inwards (:func:`_radius_to_stop`)
CHUNK = 50


def _radius_to_stop(body: Body, pts: np.ndarray, from_end: np.ndarray, least: float
                    ) -> np.ndarray:
    """(K,) the inner radius mm at the points ``pts`` (K,3) of a limb's axis, ``from_end`` (K,)
    mm from its end, from the end inwards up to the first that is ``END_RATIO`` radii from the
    end and at least ``least`` mm thick (the end bone's stop in :func:`limb_end`); NaN past it.

    Why: only the points up to the stop decide where the end bone and a tip bone end; measured
    ``CHUNK`` at a time they cost a fifth of all 400 (issue 35: 0.08 s CPU on the cow x4)."""
    radius = np.full(len(pts), np.nan)
    for lo in range(0, len(pts), CHUNK):
        hi = min(lo + CHUNK, len(pts))
        r = body.inner_radius(pts[lo:hi])
        radius[lo:hi] = r
        if ((r >= least) & (from_end[lo:hi] >= END_RATIO * r)).any():
            break
    return radius


def limb_end(body: Body, tree: Tree, line: np.ndarray, leaf: int, tip: bool = True
             ) -> tuple[np.ndarray, int, bool]:
    """Where a limb's end bone stops (mm).  ``line`` (K,3): the branch's polyline from its
    start out to the limb's last node ``leaf``.

    Beam theory (σ = M/W) holds at a section only some way from the load (Saint-Venant): a
    section closer to the limb's end than its own radius is inside the end cap, where a round
    end's sections shrink to a sliver and F·d/W grows without bound as the cut nears the
    surface.  So the bone ends, on the limb's axis, at the first point walking in from the
    limb's end whose distance to the end is at least ``END_RATIO`` × its radius (distance to
    the surface): on a capsule just past the cap's centre (where its medial axis ends), on a
    pointed spike at its point, but never where the section is a sliver (under a tenth of the
    limb's median area).  The axis is the line fitted to the branch's last stretch (3 branch
    radii), so a last node in a corner of a blunt end does not bend it; when that stretch
    reaches back to the branch's start (a finger with one skeleton node), the axis of the
    limb's own surface (:func:`_surface_axis`), and the bone gets a joint at the limb's base.

    With ``tip``, a tapering limb's end bone is followed by a tip bone to its point
    (:func:`_tip`).

    Returns (points (P,3), k, tipped): the bone's polyline is ``line[:k]`` then ``points``
    (1 <= k <= K; P = 1, the end point, or 2, the limb's base and its end point; with a tip
    bone (``tipped``) one more point, the tip bone's end)."""
    n = len(line)
    # The limb's own radius: the median over its nodes outside the body's ball at the
    # branch's start (those inside it measure the body, not the limb).
    r_line = body.inner_radius(line)
    own = np.linalg.norm(line - line[0], axis=1) > r_line[0]
    rad = max(float(np.median(r_line[own] if own.any() else r_line)), 1e-3 * body.size)
    axis = _end_axis(line, rad)
    if axis is None:
        return line[-1][None], max(n - 1, 1), False
    stretch, c, d = axis
    ends = body.v[body.is_used & (tree.owner[body.near_i[:, 0]] == leaf)]  # the limb's end
    base = np.zeros((0, 3))
    limb = _surface_axis(ends, line[0]) if len(stretch) == n else None
    if limb is not None:
        base, c, d = limb
        stretch = base
    far = float((ends @ d).max()) if len(ends) else float(line[-1] @ d)
    a = c + d * ((stretch[0] - c) @ d)  # the axis point level with the stretch's start
    length = far - a @ d
    if length <= 0:
        return line[-1][None], max(n - 1, 1), False
    t = np.linspace(length, 0.0, 400)  # from the end inwards
    pts = a + t[:, None] * d
    # ... and not a sliver: at least a tenth of the limb's median section area (the
    # engine's sliver rule), i.e. radius >= sqrt(0.1) x the limb's median radius.
    radius = _radius_to_stop(body, pts, length - t, math.sqrt(0.1) * rad)
    with np.errstate(invalid="ignore"):  # (NaN: beyond the stop, not measured)
        capped = length - t >= END_RATIO * radius
        ok = np.flatnonzero((radius >= math.sqrt(0.1) * rad) & capped)
    stop = pts[ok[0]] if len(ok) else a
    if tip:
        more = _tip(body, pts, radius, capped, stop, ok[0] if len(ok) else len(t) - 1)
        if more is not None:
            return (np.vstack([base, stop, more]),
                    1 if len(base) else max(n - len(stretch) + 1, 1), True)
    if len(base):  # a joint at the limb's base only if the straight bone would leave the mesh
        s = np.linspace(0.0, 1.0, 50)[:, None]
        if (body.inner_radius(line[0] + s * (stop - line[0])) > 0).all():
            return stop[None], 1, False
        return np.vstack([base, stop]), 1, False
    k = n - len(stretch) + 1  # the bone keeps the nodes before the last stretch
    return stop[None], max(k, 1), False
