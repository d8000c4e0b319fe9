"""Real rigged models of tests/data (or $OSTEON_DATA) by name, scaled to a print size, and
midpoint-subdivided copies (weights interpolated) for the ~100k and 1M+ face sizes. Used by the
tests and, through ``bench/models.py``, by the benchmarks. Units: mm."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import osteon
from osteon.io import load_model
from scipy import sparse

DATA = Path(os.environ.get("OSTEON_DATA", Path(__file__).resolve().parents[1] / "data"))


def subdivide(vertices: np.ndarray, faces: np.ndarray, weights):
    """One 1-to-4 midpoint subdivision; new vertices get the mean weights of their edge."""
    f = np.asarray(faces, dtype=np.int64)
    edges = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    edges.sort(axis=1)
    unique, inverse = np.unique(edges, axis=0, return_inverse=True)
    inverse = inverse.ravel()
    nv = len(vertices)
    mid = nv + inverse.reshape(3, -1).T  # (F,3): midpoint of edges 01, 12, 20
    a, b, c = f[:, 0], f[:, 1], f[:, 2]
    m01, m12, m20 = mid[:, 0], mid[:, 1], mid[:, 2]
    new_faces = np.concatenate([
        np.stack([a, m01, m20], 1), np.stack([m01, b, m12], 1),
        np.stack([m20, m12, c], 1), np.stack([m01, m12, m20], 1),
    ])
    new_vertices = np.concatenate([vertices, 0.5 * (vertices[unique[:, 0]] + vertices[unique[:, 1]])])
    ne = len(unique)
    rows = np.concatenate([np.arange(nv), nv + np.arange(ne), nv + np.arange(ne)])
    cols = np.concatenate([np.arange(nv), unique[:, 0], unique[:, 1]])
    vals = np.concatenate([np.ones(nv), np.full(ne, 0.5), np.full(ne, 0.5)])
    interp = sparse.csr_matrix((vals, (rows, cols)), shape=(nv + ne, nv))
    return new_vertices, new_faces.astype(np.int32), (interp @ weights).tocsr()


def load(name: str, height_mm: float = 120.0, subdivisions: int = 0):
    """(vertices, faces, skeleton, weights) of a named model: 'bow-like' RigNet 2982, 'arm',
    'cow', 'elephant', 'cheburashka'."""
    paths = {
        "rignet2982": (DATA / "RigNet/2982_ori.obj", None, None),
        "rignet11814": (DATA / "RigNet/11814_ori.obj", None, None),
        "arm": (DATA / "libigl-tutorial-data/arm.obj", None, None),
        "elephant": (DATA / "libigl-tutorial-data/elephant.obj", None, None),
        "cheburashka": (DATA / "Hyperspectral-Inverse-Skinning/cheburashka.obj",
                        DATA / "Hyperspectral-Inverse-Skinning/cheburashka.tgf",
                        DATA / "Hyperspectral-Inverse-Skinning/cheburashka.DMAT"),
        "cow": (DATA / "Hyperspectral-Inverse-Skinning/cow_clean.obj",
                DATA / "Hyperspectral-Inverse-Skinning/cow.tgf",
                DATA / "Hyperspectral-Inverse-Skinning/cow.DMAT"),
    }
    mesh, skel, weights = paths[name]
    m = load_model(mesh, skeleton=skel, weights=weights, height_mm=height_mm)
    v, f, w = np.asarray(m.vertices), np.asarray(m.faces, dtype=np.int32), m.weights
    for _ in range(subdivisions):
        v, f, w = subdivide(v, f, w)
    sk = m.skeleton if isinstance(m.skeleton, osteon.Skeleton) else osteon.Skeleton(
        m.heads, m.tails, m.parents, m.bone_names)
    return v, f, sk, w
