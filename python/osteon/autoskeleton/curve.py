"""Step 1: simplify the mesh and compute its curve skeleton with pygel3d (units: mm).

pygel3d's local-separator skeletons (``pygel3d.graph.LS_skeleton_and_map`` /
``MSLS_skeleton_and_map``, MIT, Bærentzen & Rotenberg, "Skeletonization via local separators",
ACM TOG 2021) on a quadric-simplified copy of the mesh."""

from __future__ import annotations

import contextlib
import os
import sys
from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass
class CurveSkeleton:
    """pygel3d's curve skeleton of the simplified mesh.

    spos (S,3) mm: simplified mesh vertices; sedges (E,2): its edges (i < j); npos (N,3) mm:
    skeleton nodes; kedges (K,2): skeleton edges; smap (S,): simplified vertex -> skeleton node
    (may hold -1 or out-of-range values, see :func:`osteon.autoskeleton.tree.fix_map`);
    surface: ``pygel3d.hmesh.MeshDistance`` of the full mesh (signed distance mm, < 0 inside)."""

    spos: np.ndarray
    sedges: np.ndarray
    npos: np.ndarray
    kedges: np.ndarray
    smap: np.ndarray
    surface: Any


def curve_skeleton(v: np.ndarray, f: np.ndarray, target: int, deterministic: bool = True
                   ) -> CurveSkeleton:
    """pygel3d skeleton of the mesh (v (V,3) mm, f (F,3)) simplified to about ``target``
    vertices; ``deterministic``: every vertex grows a separator (no libc ``rand()``)."""
    try:
        from pygel3d import graph, hmesh
    except ImportError as exc:  # pragma: no cover - pygel3d is a dependency
        raise ImportError("auto_skeleton needs pygel3d (pip install pygel3d)") from exc
    used = np.unique(f)
    m = hmesh.Manifold.from_triangles(v, f)
    if len(m.positions()) < len(used):
        raise ValueError("mesh is not manifold enough to skeletonise (pygel3d dropped vertices)")
    # Distance to the full mesh's surface (GEL's MeshDistance keeps its own copy of the
    # triangles, so the simplification below does not change it).
    surface = hmesh.MeshDistance(m)
    if len(used) > target:
        hmesh.quadric_simplify(m, target / len(used))
        m.cleanup()
    g = graph.from_mesh(m)
    pos = np.array(g.positions(), dtype=np.float64)
    sedges = graph_edges(g, len(pos))
    with quiet_stdout():  # GEL prints progress lines to C stdout
        if deterministic:  # every vertex grows a separator: no rand(), same result each run
            skel, mapping = graph.LS_skeleton_and_map(g, sampling=False)
        else:  # GEL samples with libc rand() from several threads: differs run to run
            skel, mapping = graph.MSLS_skeleton_and_map(g)
    npos = np.array(skel.positions(), dtype=np.float64)
    kedges = graph_edges(skel, len(npos))
    vmap = np.fromiter(mapping, dtype=np.int64, count=len(pos))
    return CurveSkeleton(pos, sedges, npos, kedges, vmap, surface)


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
    """(E,2) edges of a pygel3d graph (each once, i < j)."""
    pairs = [(i, j) for i in g.nodes() for j in g.neighbors(i) if i < j]
    if not pairs:
        return np.zeros((0, 2), np.int64)
    return np.array(pairs, dtype=np.int64)
