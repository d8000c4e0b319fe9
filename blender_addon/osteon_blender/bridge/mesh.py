"""Mesh data <-> NumPy: positions (posed, rest, live), triangles, the vertex selection."""

from __future__ import annotations

import numpy as np

from ..errors import OsteonError
from ._math import matrix_np, transform

# modifiers that only move vertices (everything else may change the vertex count)
_DEFORM_ONLY = {
    "ARMATURE", "CAST", "CURVE", "DISPLACE", "HOOK", "LAPLACIANDEFORM", "LAPLACIANSMOOTH",
    "LATTICE", "MESH_DEFORM", "SHRINKWRAP", "SIMPLE_DEFORM", "SMOOTH", "CORRECTIVE_SMOOTH",
    "SURFACE_DEFORM", "WARP", "WAVE", "MESH_CACHE", "MESH_SEQUENCE_CACHE", "DATA_TRANSFER",
    "NORMAL_EDIT", "WEIGHTED_NORMAL", "UV_PROJECT", "UV_WARP", "VERTEX_WEIGHT_EDIT",
    "VERTEX_WEIGHT_MIX", "VERTEX_WEIGHT_PROXIMITY",
}


def read_co(mesh, out: np.ndarray) -> None:
    """Vertex coordinates into a (V*3,) float32 array: the ``position`` attribute where
    Blender has one (3.5+, ~100x faster than ``vertices.co`` in 4.x), else ``vertices``."""
    attr = mesh.attributes.get("position")
    if attr is not None and attr.data_type == "FLOAT_VECTOR" and attr.domain == "POINT":
        attr.data.foreach_get("vector", out)
    else:
        mesh.vertices.foreach_get("co", out)


def select_vertices(mesh, indices: np.ndarray) -> None:
    """Vertex selection of a mesh datablock (Object Mode): exactly the vertices ``indices``
    (int array) selected; edges and faces selected where all their vertices are (bulk
    ``foreach_get/foreach_set``)."""
    nv = len(mesh.vertices)
    sel = np.zeros(nv, dtype=bool)
    sel[np.asarray(indices, dtype=np.int64)] = True
    mesh.vertices.foreach_set("select", sel)
    ev = np.empty(len(mesh.edges) * 2, dtype=np.int32)
    mesh.edges.foreach_get("vertices", ev)
    mesh.edges.foreach_set("select", sel[ev.reshape(-1, 2)].all(axis=1))
    corners = corner_vertices(mesh)
    npoly = len(mesh.polygons)
    if npoly:
        start = np.empty(npoly, dtype=np.int32)
        mesh.polygons.foreach_get("loop_start", start)
        all_in = np.logical_and.reduceat(sel[corners], start) if len(corners) else np.zeros(0, bool)
        mesh.polygons.foreach_set("select", all_in)
    mesh.update()


def evaluated_positions(obj, depsgraph) -> np.ndarray:
    """World-space (V, 3) float64 positions of the POSED, evaluated mesh (Blender units).

    Raises OsteonError when modifiers change the vertex count (the stress layer is
    per vertex of the original mesh)."""
    ob_eval = obj.evaluated_get(depsgraph)
    me = ob_eval.data
    n = len(me.vertices)
    if n != len(obj.data.vertices):
        bad = [m.name for m in obj.modifiers if m.show_viewport and m.type not in _DEFORM_ONLY]
        raise OsteonError(
            f"Mesh '{obj.name}': the evaluated mesh has {n} vertices, the mesh "
            f"{len(obj.data.vertices)}; disable topology-changing modifiers in the viewport "
            f"({', '.join(bad) or 'e.g. Subdivision, Mirror'}) and analyse again")
    co = np.empty(n * 3, dtype=np.float32)
    read_co(me, co)
    return transform(co.reshape(n, 3), matrix_np(ob_eval.matrix_world))


def local_positions(mesh) -> np.ndarray:
    """(V, 3) float64 vertex coordinates of a mesh datablock, object space."""
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    read_co(mesh, co)
    return co.reshape(-1, 3).astype(np.float64)


def corner_vertices(mesh) -> np.ndarray:
    """(L,) int32 vertex index of every face corner (loop)."""
    out = np.empty(len(mesh.loops), dtype=np.int32)
    attr = mesh.attributes.get(".corner_vert")  # Blender 3.6+: a plain int attribute (fast)
    if attr is not None and attr.domain == "CORNER" and len(attr.data) == len(out):
        attr.data.foreach_get("value", out)
    else:
        mesh.loops.foreach_get("vertex_index", out)
    return out


def triangles(mesh) -> np.ndarray:
    """(F, 3) int32 triangles of a mesh datablock: triangles and quads split in NumPy
    (a quad along its 0-2 diagonal), meshes with n-gons through Blender's own
    loop triangulation (which handles concave polygons)."""
    npoly = len(mesh.polygons)
    sizes = np.empty(npoly, dtype=np.int32)
    mesh.polygons.foreach_get("loop_total", sizes)
    if npoly == 0 or sizes.max() > 4:
        mesh.calc_loop_triangles()
        tri = np.empty(len(mesh.loop_triangles) * 3, dtype=np.int32)
        mesh.loop_triangles.foreach_get("vertices", tri)
        return tri.reshape(-1, 3)
    start = np.empty(npoly, dtype=np.int32)
    mesh.polygons.foreach_get("loop_start", start)
    corner = corner_vertices(mesh)
    first = corner[start]
    tris = [np.stack([first, corner[start + 1], corner[start + 2]], axis=1)]
    quads = start[sizes == 4]
    if len(quads):
        tris.append(np.stack([corner[quads], corner[quads + 2], corner[quads + 3]], axis=1))
    return np.concatenate(tris)


def set_local_positions(mesh, co: np.ndarray):
    mesh.vertices.foreach_set("co", np.ascontiguousarray(co, dtype=np.float32).ravel())
    mesh.update()


def evaluated_positions_into(obj, depsgraph, buf: np.ndarray | None = None
                             ) -> tuple[np.ndarray, np.ndarray]:
    """Live-mode variant of :func:`evaluated_positions`: the raw float32 object-space
    coordinates of the evaluated mesh read into ``buf`` (reused between calls when its
    size fits) and the (4, 4) world matrix, without the float64 world transform (the
    caller fuses it with the mm scale in one pass).  Same vertex-count check."""
    ob_eval = obj.evaluated_get(depsgraph)
    me = ob_eval.data
    n = len(me.vertices)
    if n != len(obj.data.vertices):
        evaluated_positions(obj, depsgraph)  # raises the OsteonError that explains it
        raise OsteonError(f"Mesh '{obj.name}': evaluated vertex count {n} != {len(obj.data.vertices)}")
    if buf is None or buf.shape != (n, 3) or buf.dtype != np.float32:
        buf = np.empty((n, 3), dtype=np.float32)
    read_co(me, buf.reshape(-1))     # the position attribute: ~0.1 ms, not 3-7 ms (107k)
    return buf, matrix_np(ob_eval.matrix_world)


def topology_key(obj) -> tuple:
    """Cheap key of what a reusable analyzer depends on in the mesh: the datablock, its
    vertex/face/loop counts and the vertex-group names (no per-element reads)."""
    me = obj.data
    return (me.as_pointer(), len(me.vertices), len(me.polygons), len(me.loops),
            tuple(vg.name for vg in obj.vertex_groups))


def world_rest_positions(obj) -> np.ndarray:
    """(V, 3) float64 world-space positions of the mesh datablock (no modifiers), Blender units."""
    return transform(local_positions(obj.data), matrix_np(obj.matrix_world))
