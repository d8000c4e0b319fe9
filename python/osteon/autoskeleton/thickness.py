"""Whether a point of a mesh is thick enough to print (issue 35): the one measure the auto
skeleton's steps (the tip bones of ``ends``, the thin branches of ``thin``, the small pieces'
tips of ``piece_tips``, the pruning of unprintable branches) and the bench
(``tests/python/extremities.py``) share. Units: mm.

A point is printable with a material when the solid's local thickness there is at least the
material's minimum printable thickness (``min_thickness_mm`` of :mod:`osteon.materials`: FDM
0.8 mm, two lines of a 0.4 mm nozzle; resin 0.3 mm; SLS 0.7 mm). The local thickness at a
point is the diameter of the largest ball centred there inside the solid: twice its distance
to the surface, its inner radius. (Hildebrand & Rüegsegger, J. Microsc. 185:67-75, 1997,
define a point's local thickness as the diameter of the largest sphere that contains it and
fits inside the solid; on a limb's axis, where the auto skeleton's bones run and end, the
ball centred at the point is that sphere.) A bone's end needs the section there to print,
so it is the point itself that must be thick enough, not the thickest place near it.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np


def local_thickness(inner_radius: np.ndarray | float) -> np.ndarray:
    """The local thickness mm at points whose distance to the surface is ``inner_radius``
    mm (0 or NaN outside the solid)."""
    return 2.0 * np.asarray(inner_radius, dtype=np.float64)


def printable(inner_radius: np.ndarray | float, min_t: float) -> np.ndarray:
    """(N,) bool: the points of inner radius ``inner_radius`` mm are at least ``min_t`` mm
    thick (NaN: False)."""
    return local_thickness(inner_radius) >= min_t


def ball_points(center: np.ndarray, radius: float, n: int = 9) -> np.ndarray:
    """(K,3) the points of an n x n x n grid over the cube round ``center`` (3,) of half-side
    ``radius`` that lie in the ball of that radius."""
    axis = np.linspace(-1.0, 1.0, n)
    grid = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), -1).reshape(-1, 3)
    grid = grid[(grid * grid).sum(1) <= 1.0]
    return np.asarray(center, dtype=np.float64) + radius * grid


def printable_within(inner_radius: Callable[[np.ndarray], np.ndarray], center: np.ndarray,
                     reach: float, min_t: float, n: int = 9) -> bool:
    """Whether some point within ``reach`` mm of ``center`` (3,) is printable (``printable``
    of ``inner_radius(points)``, on the points of :func:`ball_points`): where a bone may end
    within ``reach`` of a tip and its section still print."""
    return bool(printable(inner_radius(ball_points(center, reach, n)), min_t).any())
