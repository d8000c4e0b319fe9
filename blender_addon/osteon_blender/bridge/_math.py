"""Matrix helpers shared by the bridge modules (NumPy, no Blender data read)."""

from __future__ import annotations

import numpy as np
from mathutils import Matrix


def matrix_np(m: Matrix) -> np.ndarray:
    return np.array([list(r) for r in m], dtype=np.float64)


def transform(points: np.ndarray, m: np.ndarray) -> np.ndarray:
    """points (N, 3) -> (N, 3) float64, affine 4x4 ``m`` applied (column by column: faster
    than a matmul with an inner size of 3)."""
    out = np.empty((len(points), 3), dtype=np.float64)
    for i in range(3):
        np.multiply(points[:, 0], m[i, 0], out=out[:, i])
        out[:, i] += points[:, 1] * m[i, 1]
        out[:, i] += points[:, 2] * m[i, 2]
        out[:, i] += m[i, 3]
    return out


def parent_depth(item) -> int:
    """How many parents are above ``item`` (a bone or an object: anything with ``.parent``)."""
    d = 0
    while item.parent is not None:
        item, d = item.parent, d + 1
    return d
