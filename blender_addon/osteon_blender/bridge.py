"""The one place where Blender data becomes NumPy arrays and back.

Bulk ``foreach_get``/``foreach_set`` everywhere.  bpy offers no bulk access to
deform weights: :func:`vertex_weights_csr` reads them through a temporary Geometry
Nodes evaluation (falling back to the one per-vertex Python loop), and
:class:`WeightCache` keeps them between runs.

Everything returned is in world space and Blender units unless a name says mm.
These functions are reused by the live mode (issue 7): ``evaluated_positions``
+ ``triangles`` + ``skeleton_arrays`` give the engine its input, and
``write_point_colors`` writes the stress layer.
"""

from __future__ import annotations

from dataclasses import dataclass

import bpy
import numpy as np
from mathutils import Matrix

from .core import OsteonError

LAYER = "osteon_stress"
SAVED_POSE_KEY = "osteon_saved_pose"

# A deform bone shorter than this fraction of the skeleton's size has no usable axis.  Blender
# up to 4.x deletes zero-length bones when leaving Edit Mode; 5.2 keeps them (length ~2e-6).
MIN_BONE_LENGTH_REL = 1e-5

# modifiers that only move vertices (everything else may change the vertex count)
_DEFORM_ONLY = {
    "ARMATURE", "CAST", "CURVE", "DISPLACE", "HOOK", "LAPLACIANDEFORM", "LAPLACIANSMOOTH",
    "LATTICE", "MESH_DEFORM", "SHRINKWRAP", "SIMPLE_DEFORM", "SMOOTH", "CORRECTIVE_SMOOTH",
    "SURFACE_DEFORM", "WARP", "WAVE", "MESH_CACHE", "MESH_SEQUENCE_CACHE", "DATA_TRANSFER",
    "NORMAL_EDIT", "WEIGHTED_NORMAL", "UV_PROJECT", "UV_WARP", "VERTEX_WEIGHT_EDIT",
    "VERTEX_WEIGHT_MIX", "VERTEX_WEIGHT_PROXIMITY",
}


# --------------------------------------------------------------------------- objects


def armature_of(obj) -> bpy.types.Object | None:
    """The armature object of the first enabled Armature modifier of ``obj``."""
    for mod in obj.modifiers:
        if mod.type == "ARMATURE" and mod.object is not None and mod.show_viewport:
            return mod.object
    return None


def meshes_of_armature(arm, scene) -> list:
    return [o for o in scene.objects if o.type == "MESH" and armature_of(o) is arm]


def find_target(context) -> tuple:
    """(mesh object, armature object) for the active object, or OsteonError."""
    obj = context.active_object if hasattr(context, "active_object") else None
    if obj is None:
        obj = getattr(context.view_layer.objects, "active", None)
    if obj is None:
        raise OsteonError("No active object: select a mesh that has an Armature modifier")
    if obj.type == "ARMATURE":
        cands = meshes_of_armature(obj, context.scene)
        if not cands:
            raise OsteonError(f"Armature '{obj.name}' deforms no mesh (no Armature modifier uses it)")
        if len(cands) > 1:
            sel = [o for o in cands if o.select_get()]
            if len(sel) != 1:
                names = ", ".join(sorted(o.name for o in cands))
                raise OsteonError(f"Armature '{obj.name}' deforms several meshes ({names}): "
                                  "make the one to analyse active")
            cands = sel
        obj = cands[0]
    if obj.type != "MESH":
        raise OsteonError(f"Active object '{obj.name}' is a {obj.type.lower()}, not a mesh: "
                          "select a rigged mesh")
    if obj.mode == "EDIT":
        raise OsteonError(f"Mesh '{obj.name}' is in Edit Mode: leave Edit Mode first")
    arm = armature_of(obj)
    if arm is None or arm.type != "ARMATURE":
        raise OsteonError(f"Mesh '{obj.name}' has no Armature modifier with an armature object")
    if len(obj.data.vertices) == 0:
        raise OsteonError(f"Mesh '{obj.name}' has no vertices")
    return obj, arm


# --------------------------------------------------------------------------- mesh


def _matrix_np(m: Matrix) -> np.ndarray:
    return np.array([list(r) for r in m], dtype=np.float64)


def _transform(points: np.ndarray, m: np.ndarray) -> np.ndarray:
    """points (N, 3) -> (N, 3) float64, affine 4x4 ``m`` applied (column by column: faster
    than a matmul with an inner size of 3)."""
    out = np.empty((len(points), 3), dtype=np.float64)
    for i in range(3):
        np.multiply(points[:, 0], m[i, 0], out=out[:, i])
        out[:, i] += points[:, 1] * m[i, 1]
        out[:, i] += points[:, 2] * m[i, 2]
        out[:, i] += m[i, 3]
    return out


def read_co(mesh, out: np.ndarray) -> None:
    """Vertex coordinates into a (V*3,) float32 array: the ``position`` attribute where
    Blender has one (3.5+, ~100x faster than ``vertices.co`` in 4.x), else ``vertices``."""
    attr = mesh.attributes.get("position")
    if attr is not None and attr.data_type == "FLOAT_VECTOR" and attr.domain == "POINT":
        attr.data.foreach_get("vector", out)
    else:
        mesh.vertices.foreach_get("co", out)


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
    return _transform(co.reshape(n, 3), _matrix_np(ob_eval.matrix_world))


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


# --------------------------------------------------------------------------- skeleton


@dataclass
class SkeletonArrays:
    names: list[str]          # deform bones, armature order
    heads: np.ndarray         # (B, 3) world, posed, Blender units
    tails: np.ndarray         # (B, 3)
    parents: np.ndarray       # (B,) int, nearest deform ancestor, -1 = root
    x_axes: np.ndarray | None = None  # (B, 3) world unit X axis of each posed bone (roll)
    bone_axes: np.ndarray | None = None  # (B, 3, 3) world unit X, Y, Z axes of each posed bone
    # joint rigs (osteon.io.joints): the Blender tails before the engine's segments replaced
    # them, which bones changed, the local axes (scale X, scale Z, length) of each bone, and
    # (B, 3) world direction of the local axis each bone scales across (its "length" slot),
    # passed to osteon.correct as bone_long_axes
    blender_tails: np.ndarray | None = None
    segment_changed: np.ndarray | None = None
    scale_slots: np.ndarray | None = None
    long_axes: np.ndarray | None = None


def skeleton_arrays(arm) -> SkeletonArrays:
    """Posed deform bones of an armature object in world space."""
    bones = arm.data.bones
    deform = [b.name for b in bones if b.use_deform]
    if not deform:
        raise OsteonError(f"Armature '{arm.name}' has no deform bones")
    idx = {n: i for i, n in enumerate(deform)}
    nb = len(deform)
    pb = arm.pose.bones
    head = np.empty((nb, 3))
    tail = np.empty((nb, 3))
    parents = np.full(nb, -1, dtype=np.int64)
    x_axes = np.empty((nb, 3))
    axes = np.empty((nb, 3, 3))
    for i, name in enumerate(deform):
        p = pb[name]
        head[i] = p.head
        tail[i] = p.tail
        x_axes[i] = p.x_axis
        axes[i] = (p.x_axis, p.y_axis, p.z_axis)
        anc = bones[name].parent
        while anc is not None and anc.name not in idx:
            anc = anc.parent
        if anc is not None:
            parents[i] = idx[anc.name]
    mw = _matrix_np(arm.matrix_world)
    head_w, tail_w = _transform(head, mw), _transform(tail, mw)
    _check_bone_lengths(arm.name, deform, head_w, tail_w)
    x_world = x_axes @ mw[:3, :3].T
    x_world /= np.linalg.norm(x_world, axis=1, keepdims=True)
    axes_w = axes @ mw[:3, :3].T
    axes_w /= np.linalg.norm(axes_w, axis=2, keepdims=True)
    return SkeletonArrays(deform, head_w, tail_w, parents, x_world, axes_w)


def use_joint_segments(sk: SkeletonArrays, vertices: np.ndarray, weights) -> SkeletonArrays:
    """Give the engine the bone segments a joint rig means (FBX/glTF imports: bones with
    arbitrary tails), through the wheel's one function ``osteon.io.joints.joint_segments``;
    a rig whose bones end at their children's heads is left as it is.  ``vertices`` (V, 3)
    world, same units as ``sk``; ``weights`` (V, B).  Updates ``sk`` in place: ``tails`` become
    the segments' ends, ``x_axes`` the local axis that carries the correction's scale X,
    ``scale_slots`` which local axes get (scale X, scale Z, 1) (see
    :func:`correction_pose_scales`) and ``long_axes`` the local axis that keeps scale 1, which
    the engine's correction scales across (``osteon.correct(bone_long_axes=...)``) so that the
    pose scales reproduce its vertices exactly."""
    from osteon.io import joints

    new_tails, changed = joints.joint_segments(sk.heads, sk.tails, sk.parents, vertices, weights)
    sk.blender_tails = sk.tails
    sk.segment_changed = changed
    if changed.any():
        _check_bone_lengths("(segments of the joint rig)", sk.names, sk.heads, new_tails)
        sk.tails = new_tails
        if sk.bone_axes is not None:
            sk.x_axes, sk.scale_slots = joints.cross_section_axes(new_tails - sk.heads,
                                                                  sk.bone_axes)
            sk.long_axes = sk.bone_axes[np.arange(len(sk.names)), sk.scale_slots[:, 2]]
    return sk


def correction_pose_scales(sk: SkeletonArrays, scale_x, scale_z) -> dict[str, tuple]:
    """Per bone name, the pose scale factors (x, y, z) on the bone's own local axes that
    reproduce the engine's cross-section scales: (scale X, 1, scale Z) for a bone whose Y axis is
    its segment; for a joint-rig bone whose segment lies along another local axis, that axis
    gets 1 and the two others the scales (``scale_slots``)."""
    out = {}
    for i, n in enumerate(sk.names):
        v = [1.0, 1.0, 1.0]
        slots = (0, 2, 1) if sk.scale_slots is None else tuple(int(k) for k in sk.scale_slots[i])
        v[slots[0]] = float(scale_x[i])
        v[slots[1]] = float(scale_z[i])
        out[n] = tuple(v)
    return out


def _check_bone_lengths(arm_name: str, names: list[str], head: np.ndarray,
                        tail: np.ndarray) -> None:
    """OsteonError naming the first deform bone whose (posed, world) length is below
    ``MIN_BONE_LENGTH_REL`` times the skeleton's largest extent (Blender units)."""
    length = np.linalg.norm(tail - head, axis=1)
    size = float(np.ptp(np.concatenate([head, tail]), axis=0).max())
    short = np.flatnonzero(~(length > MIN_BONE_LENGTH_REL * size))
    if short.size:
        i = int(short[0])
        raise OsteonError(f"Bone '{names[i]}' of armature '{arm_name}' has (nearly) zero length "
                          f"({length[i]:.3g} Blender units): a bone needs a head and a tail "
                          f"apart to have an axis; delete or lengthen it")


# --------------------------------------------------------------------------- weights


def _node_tree_sockets(ng) -> None:
    if hasattr(ng, "interface"):  # Blender 4.0+
        ng.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
        ng.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    else:
        ng.inputs.new("NodeSocketGeometry", "Geometry")
        ng.outputs.new("NodeSocketGeometry", "Geometry")


def _weights_via_nodes(obj, groups: list[str]):
    """Yield (group index in ``groups``, (V,) float32 weights) for every group, read in
    bulk: a temporary object sharing the mesh gets a Geometry Nodes modifier that stores
    each vertex group as a float point attribute, read with ``foreach_get``.  The
    temporary object and node group are removed again; the user's data is not touched."""
    scene = bpy.context.scene
    ng = bpy.data.node_groups.new("osteon_weights", "GeometryNodeTree")
    tmp = None
    try:
        _node_tree_sockets(ng)
        gin, gout = ng.nodes.new("NodeGroupInput"), ng.nodes.new("NodeGroupOutput")
        prev = gin.outputs[0]
        for i, name in enumerate(groups):
            na = ng.nodes.new("GeometryNodeInputNamedAttribute")
            na.data_type = "FLOAT"
            na.inputs["Name"].default_value = name
            st = ng.nodes.new("GeometryNodeStoreNamedAttribute")
            st.data_type = "FLOAT"
            st.domain = "POINT"
            st.inputs["Name"].default_value = f"osteon_w{i}"
            value = next(x for x in st.inputs if x.name == "Value" and x.type == "VALUE"
                         and x.enabled)
            out = next(x for x in na.outputs if x.type == "VALUE" and x.enabled)
            ng.links.new(prev, st.inputs["Geometry"])
            ng.links.new(out, value)
            prev = st.outputs["Geometry"]
        ng.links.new(prev, gout.inputs[0])
        tmp = bpy.data.objects.new("osteon_weights_tmp", obj.data)
        scene.collection.objects.link(tmp)
        tmp.modifiers.new("osteon_weights", "NODES").node_group = ng
        me = tmp.evaluated_get(bpy.context.evaluated_depsgraph_get()).data
        n = len(obj.data.vertices)
        if len(me.vertices) != n:
            raise RuntimeError("node evaluation changed the vertex count")
        buf = np.empty(n, dtype=np.float32)
        for i in range(len(groups)):
            me.attributes[f"osteon_w{i}"].data.foreach_get("value", buf)
            yield i, buf
    finally:
        if tmp is not None:
            bpy.data.objects.remove(tmp, do_unlink=True)
        bpy.data.node_groups.remove(ng)


def _weights_via_loop(obj, gmap: np.ndarray):
    """(rows, bone, weight) from the per-vertex ``groups`` collections (slow, always works)."""
    groups: list[int] = []
    weights: list[float] = []
    counts: list[int] = []
    ga, wa, ca = groups.append, weights.append, counts.append
    for v in obj.data.vertices:
        gs = v.groups
        ca(len(gs))
        for g in gs:
            ga(g.group)
            wa(g.weight)
    g = np.asarray(groups, dtype=np.int64)
    w = np.asarray(weights, dtype=np.float64)
    row = np.repeat(np.arange(len(counts), dtype=np.int64), np.asarray(counts, dtype=np.int64))
    ok = g < len(gmap)
    bone = np.where(ok, gmap[np.minimum(g, len(gmap) - 1)], -1)
    return row, bone, w


def vertex_weights_csr(obj, bone_names: list[str], method: str = "auto"
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertex-group weights of the groups named after ``bone_names`` as CSR arrays
    (data float64, indices int32 bone index, indptr int64) of shape (V, B).

    bpy has no bulk access to deform weights.  ``method="nodes"`` reads them through a
    temporary Geometry Nodes evaluation (~10x faster on 100k vertices; it adds and
    removes a temporary object, so not for use inside depsgraph handlers);
    ``"loop"`` walks ``vertices[i].groups`` in Python; ``"auto"`` tries nodes, then loop."""
    name_to_bone = {n: i for i, n in enumerate(bone_names)}
    gmap = np.full(max(len(obj.vertex_groups), 1), -1, dtype=np.int32)
    for vg in obj.vertex_groups:
        gmap[vg.index] = name_to_bone.get(vg.name, -1)
    if not np.any(gmap >= 0):
        raise OsteonError(f"Mesh '{obj.name}' has no vertex groups named after deform bones "
                          "of its armature")
    nv = len(obj.data.vertices)
    result = None
    if method in ("auto", "nodes"):
        used = [vg.name for vg in obj.vertex_groups if gmap[vg.index] >= 0]
        columns = _weights_via_nodes(obj, used)
        try:
            rows, bones, ws = [], [], []
            for i, buf in columns:
                nz = np.flatnonzero(buf > 0.0)
                rows.append(nz)
                bones.append(np.full(len(nz), name_to_bone[used[i]], dtype=np.int32))
                ws.append(buf[nz].astype(np.float64))
            result = (np.concatenate(rows), np.concatenate(bones), np.concatenate(ws))
        except Exception:  # any trouble: the slow exact path below
            if method == "nodes":
                raise
            result = None
        finally:
            columns.close()  # removes the temporary object and node group
    if result is None:
        result = _weights_via_loop(obj, gmap)
    row, bone, w = result
    keep = (bone >= 0) & (w > 0.0)
    row, bone, w = row[keep], bone[keep], w[keep]
    order = np.lexsort((bone, row))
    row, bone, w = row[order], bone[order], w[order]
    indptr = np.zeros(nv + 1, dtype=np.int64)
    np.cumsum(np.bincount(row, minlength=nv), out=indptr[1:])
    if len(w) == 0:
        raise OsteonError(f"Mesh '{obj.name}': its vertex groups named after bones are empty")
    return w, bone.astype(np.int32), indptr


class CSRWeights:
    """Minimal (V, B) CSR matrix with ``tocsr()`` for when SciPy is not installed (the
    engine reads any object with ``tocsr``, ``shape``, ``indptr``, ``indices``, ``data``)."""

    def __init__(self, data, indices, indptr, shape):
        self.data, self.indices, self.indptr, self.shape = data, indices, indptr, shape

    def tocsr(self):
        return self

    def toarray(self) -> np.ndarray:
        dense = np.zeros(self.shape)
        rows = np.repeat(np.arange(self.shape[0]), np.diff(self.indptr))
        np.add.at(dense, (rows, self.indices), self.data)
        return dense


def sparse_weights(csr: tuple[np.ndarray, np.ndarray, np.ndarray], n_bones: int):
    """scipy.sparse.csr_matrix (V, B) when SciPy is there, else :class:`CSRWeights`."""
    data, indices, indptr = csr
    shape = (len(indptr) - 1, n_bones)
    try:
        from scipy.sparse import csr_matrix
    except ImportError:
        return CSRWeights(data, indices, indptr, shape)
    return csr_matrix((data, indices, indptr), shape=shape)


class WeightCache:
    """Weights read once per mesh datablock and vertex-group layout (for repeated runs)."""

    def __init__(self):
        self._key = None
        self._value = None

    def get(self, obj, bone_names: list[str], method: str = "auto"):
        key = (obj.data.as_pointer(), len(obj.data.vertices), tuple(bone_names),
               tuple(vg.name for vg in obj.vertex_groups))
        if key != self._key:
            self._value = vertex_weights_csr(obj, bone_names, method)
            self._key = key
        return self._value

    def clear(self):
        self._key = self._value = None


# --------------------------------------------------------------------------- colours


def write_point_colors(mesh, rgba: np.ndarray, name: str = LAYER):
    """Write (V, 4) RGBA into a FLOAT_COLOR point attribute and make it the active
    (and render) colour.  Only this attribute of the mesh is touched."""
    attr = mesh.attributes.get(name)
    if attr is not None and (attr.domain != "POINT" or attr.data_type != "FLOAT_COLOR"):
        mesh.attributes.remove(attr)
        attr = None
    if attr is None:
        attr = mesh.attributes.new(name, "FLOAT_COLOR", "POINT")
    attr.data.foreach_set("color", np.ascontiguousarray(rgba, dtype=np.float32).ravel())
    ca = getattr(mesh, "color_attributes", None)
    if ca is not None:
        if hasattr(ca, "active_color_name"):
            ca.active_color_name = name
        elif hasattr(ca, "active_color"):
            ca.active_color = mesh.color_attributes[name]
        if hasattr(ca, "render_color_index"):
            ca.render_color_index = ca.find(name)
        if hasattr(ca, "active_color_index"):
            ca.active_color_index = ca.find(name)
    mesh.update_tag()
    return attr


def read_point_colors(mesh, name: str = LAYER) -> np.ndarray | None:
    attr = mesh.attributes.get(name)
    if attr is None:
        return None
    out = np.empty(len(attr.data) * 4, dtype=np.float32)
    attr.data.foreach_get("color", out)
    return out.reshape(-1, 4)


def remove_point_colors(mesh, name: str = LAYER) -> bool:
    attr = mesh.attributes.get(name)
    if attr is None:
        return False
    mesh.attributes.remove(attr)
    mesh.update_tag()
    return True


def show_colors_in_viewports(screen_owner=None):
    """Solid shading shows the colour attribute in every open 3D viewport (UI only)."""
    wm = getattr(bpy.context, "window_manager", None)
    for win in getattr(wm, "windows", None) or []:
        for area in win.screen.areas:
            if area.type != "VIEW_3D":
                continue
            for space in area.spaces:
                if space.type == "VIEW_3D" and space.shading.type == "SOLID":
                    space.shading.color_type = "VERTEX"


# --------------------------------------------------------------------------- pose scales


def pose_scales(arm) -> dict[str, tuple]:
    return {p.name: tuple(p.scale) for p in arm.pose.bones}


def has_saved_pose(arm) -> bool:
    return SAVED_POSE_KEY in arm


def _depth(bone) -> int:
    d = 0
    while bone.parent is not None:
        bone = bone.parent
        d += 1
    return d


def _xz(scale) -> tuple[float, float]:
    """A bone's cross-section scale as (x, z): a number scales both axes."""
    if isinstance(scale, (tuple, list)):
        return float(scale[0]), float(scale[-1])
    return float(scale), float(scale)


def _xyz(scale) -> tuple[float, float, float]:
    """A bone's pose scale factors on its local (x, y, z): a number s is (s, 1, s), a pair
    (x, z) is (x, 1, z), a triple is itself (joint rigs: see :func:`correction_pose_scales`)."""
    if isinstance(scale, (tuple, list)):
        if len(scale) == 3:
            return float(scale[0]), float(scale[1]), float(scale[2])
        return float(scale[0]), 1.0, float(scale[1])
    return float(scale), 1.0, float(scale)


def apply_bone_scales(context, arm, scales: dict, tol: float = 1e-7) -> list[str]:
    """Scale pose bones across their axis (pose scale x and z times s, y kept; a value is s
    for both axes or an (x, z) pair, as ``osteon.Correction.bone_scale_x/_z``) such that
    Blender's armature deformation reproduces the engine's skinning: children of a
    scaled bone do not inherit the scale (``inherit_scale = 'NONE'``) and get a pose
    location that puts their head back where it was, so they keep shape and place.

    The previous state of every touched bone is stored on the armature object
    (ID property ``osteon_saved_pose``) for :func:`restore_pose`.  A previous
    correction is restored first, so applying is idempotent.  Returns the names of
    the bones that were scaled."""
    restore_pose(context, arm)
    bones = arm.data.bones
    pb = arm.pose.bones
    scaled = [n for n, s in scales.items()
              if max(abs(v - 1.0) for v in _xyz(s)) > tol and n in pb]
    if not scaled:
        return []
    children = sorted({c.name for n in scaled for c in bones[n].children},
                      key=lambda n: _depth(bones[n]))
    touched = sorted(set(scaled) | set(children))
    saved = {n: {"scale": list(pb[n].scale), "location": list(pb[n].location),
                 "inherit_scale": bones[n].inherit_scale} for n in touched}
    heads = {n: pb[n].matrix.translation.copy() for n in children}
    arm[SAVED_POSE_KEY] = {"bones": saved}
    try:
        for n in scaled:
            kx, ky, kz = _xyz(scales[n])
            sx, sy, sz = pb[n].scale
            pb[n].scale = (sx * kx, sy * ky, sz * kz)
        for n in children:
            bones[n].inherit_scale = "NONE"
        by_depth: dict[int, list[str]] = {}
        for n in children:
            by_depth.setdefault(_depth(bones[n]), []).append(n)
        for d in sorted(by_depth):
            context.view_layer.update()
            for n in by_depth[d]:
                p = pb[n]
                m = p.matrix.copy()
                m.translation = heads[n]
                basis = arm.convert_space(pose_bone=p, matrix=m, from_space="POSE", to_space="LOCAL")
                p.location = basis.translation
        context.view_layer.update()
    except Exception:
        restore_pose(context, arm)
        raise
    return scaled


def restore_pose(context, arm) -> bool:
    """Undo :func:`apply_bone_scales`: the user's pose scales, locations, inherit modes."""
    if SAVED_POSE_KEY not in arm:
        return False
    saved = arm[SAVED_POSE_KEY].to_dict().get("bones", {})
    pb = arm.pose.bones
    bones = arm.data.bones
    for n, st in saved.items():
        if n not in pb:
            continue
        pb[n].scale = st["scale"]
        pb[n].location = st["location"]
        bones[n].inherit_scale = st["inherit_scale"]
    del arm[SAVED_POSE_KEY]
    context.view_layer.update()
    return True


def correction_ratios(arm) -> dict[str, tuple]:
    """Per bone, the cross-section scales (x, z) the current correction applies, or
    (x, y, z) where it also scales the bone's Y axis (a joint-rig bone, see
    :func:`correction_pose_scales`)."""
    if SAVED_POSE_KEY not in arm:
        return {}
    saved = arm[SAVED_POSE_KEY].to_dict().get("bones", {})
    out = {}
    for n, st in saved.items():
        p = arm.pose.bones.get(n)
        if p is not None and all(v != 0.0 for v in st["scale"]):
            r = tuple(float(p.scale[k] / st["scale"][k]) for k in range(3))
            if max(abs(v - 1.0) for v in r) > 1e-7:
                out[n] = r if abs(r[1] - 1.0) > 1e-7 else (r[0], r[2])
    return out


# --------------------------------------------------------------------------- apply


def bake_scales_into_mesh(obj, arm, ratios: dict, bone_names: list[str],
                          csr: tuple[np.ndarray, np.ndarray, np.ndarray]) -> np.ndarray:
    """New rest coordinates (mesh object space) with each bone's cross-section scaled
    about its REST axis, blended by normalised weights (zero-weight vertices kept)."""
    data, indices, indptr = csr
    co = local_positions(obj.data)
    v = len(co)
    rows = np.repeat(np.arange(v), np.diff(indptr))
    total = np.zeros(v)
    np.add.at(total, rows, data)
    to_arm = _matrix_np(arm.matrix_world.inverted() @ obj.matrix_world)
    from_arm = np.linalg.inv(to_arm)
    pa = _transform(co, to_arm)
    delta = np.zeros_like(pa)
    for name, s in ratios.items():
        if name not in bone_names:
            continue
        b = bone_names.index(name)
        sel = indices == b
        if not np.any(sel):
            continue
        r = rows[sel]
        w = data[sel] / np.where(total[r] > 0, total[r], 1.0)
        rest = _matrix_np(arm.data.bones[name].matrix_local)
        kx, ky, kz = _xyz(s)
        d = rest @ np.diag([kx, ky, kz, 1.0]) @ np.linalg.inv(rest)
        p = pa[r]
        delta[r] += w[:, None] * (_transform(p, d) - p)
    return _transform(pa + delta, from_arm)


def set_local_positions(mesh, co: np.ndarray):
    mesh.vertices.foreach_set("co", np.ascontiguousarray(co, dtype=np.float32).ravel())
    mesh.update()


# --------------------------------------------------------------------------- live mode (issue 7)


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
    me.vertices.foreach_get("co", buf.ravel())
    return buf, _matrix_np(ob_eval.matrix_world)


def topology_key(obj) -> tuple:
    """Cheap key of what a reusable analyzer depends on in the mesh: the datablock, its
    vertex/face/loop counts and the vertex-group names (no per-element reads)."""
    me = obj.data
    return (me.as_pointer(), len(me.vertices), len(me.polygons), len(me.loops),
            tuple(vg.name for vg in obj.vertex_groups))


def tag_redraw_view3d(region_types: tuple = ("UI", "WINDOW")):
    """Redraw the sidebars / main regions of every open 3D viewport (UI only; no-op headless)."""
    wm = getattr(bpy.context, "window_manager", None)
    for win in getattr(wm, "windows", None) or []:
        for area in win.screen.areas:
            if area.type != "VIEW_3D":
                continue
            for region in area.regions:
                if region.type in region_types:
                    region.tag_redraw()


# --------------------------------------------------------------------------- print direction


def world_matrices(objects) -> dict:
    """name -> a copy of matrix_world, (4, 4) float64, for each object."""
    return {o.name: _matrix_np(o.matrix_world).copy() for o in objects}


def set_world_matrices(context, objects, matrices: dict) -> None:
    """Set each object's matrix_world from ``matrices`` (name -> (4, 4)), parents first."""
    for o in sorted(objects, key=lambda o: _depth(o)):
        if o.name in matrices:
            o.matrix_world = Matrix(np.asarray(matrices[o.name], float).tolist())
            context.view_layer.update()


def _depth(o) -> int:
    d = 0
    while o.parent is not None:
        o, d = o.parent, d + 1
    return d


def rotate_objects(context, objects, rotation: np.ndarray, centre: np.ndarray) -> dict:
    """Turn ``objects`` rigidly by ``rotation`` (3, 3) about the world point ``centre`` (3,)
    (Blender units): new matrix_world = T(c) R T(-c) old. An object whose parent is also turned
    follows its parent and is not turned again. Returns the old matrices (name -> (4, 4))."""
    objects = list(objects)
    old = world_matrices(objects)
    t = np.eye(4)
    t[:3, :3] = np.asarray(rotation, float)
    c = np.asarray(centre, float)
    t[:3, 3] = c - t[:3, :3] @ c
    names = {o.name for o in objects}

    def follows(o) -> bool:
        p = o.parent
        while p is not None:
            if p.name in names:
                return True
            p = p.parent
        return False

    new = {o.name: t @ old[o.name] for o in objects if not follows(o)}
    set_world_matrices(context, [o for o in objects if o.name in new], new)
    return old


def arrow_empty(context, name: str, origin, direction, length: float):
    """A single-arrow empty ``name`` at ``origin`` (3,) whose arrow (local +Z) points along
    ``direction`` (3,), ``length`` Blender units long; reused if it exists (a preview, never
    the user's mesh)."""
    ob = bpy.data.objects.get(name)
    if ob is None or ob.type != "EMPTY":
        ob = bpy.data.objects.new(name, None)
    if context.scene.collection.objects.get(ob.name) is None:
        context.scene.collection.objects.link(ob)
    ob.empty_display_type = "SINGLE_ARROW"
    ob.empty_display_size = float(length)
    d = np.asarray(direction, float)
    d = d / np.linalg.norm(d)
    # a rotation taking +Z to d: the transpose of the one taking d to +Z
    from osteon.orientation import rotation_to_z

    m = np.eye(4)
    m[:3, :3] = rotation_to_z(d).T
    m[:3, 3] = np.asarray(origin, float)
    ob.matrix_world = Matrix(m.tolist())
    ob.show_in_front = True
    return ob


def remove_object(name: str) -> None:
    ob = bpy.data.objects.get(name)
    if ob is not None:
        bpy.data.objects.remove(ob, do_unlink=True)


# --------------------------------------------------------------------------- make skeleton


def world_rest_positions(obj) -> np.ndarray:
    """(V, 3) float64 world-space positions of the mesh datablock (no modifiers), Blender units."""
    return _transform(local_positions(obj.data), _matrix_np(obj.matrix_world))


def build_armature(context, name: str, heads: np.ndarray, tails: np.ndarray,
                   parents: np.ndarray, names: list[str]):
    """A new Armature object (at the world origin) with one bone per row: ``heads``/``tails``
    (B, 3) world, Blender units; ``parents`` (B,) int, -1 = root.  Bones are made in Edit
    Mode (bpy has no other way); the loop is over bones (tens), not vertices."""
    data = bpy.data.armatures.new(name)
    arm = bpy.data.objects.new(name, data)
    context.collection.objects.link(arm)
    prev_active = context.view_layer.objects.active
    context.view_layer.objects.active = arm
    bpy.ops.object.mode_set(mode="EDIT")
    try:
        ebs = [data.edit_bones.new(n) for n in names]
        for i, eb in enumerate(ebs):
            eb.head = tuple(float(x) for x in heads[i])
            eb.tail = tuple(float(x) for x in tails[i])
            eb.use_deform = True
        for i, p in enumerate(np.asarray(parents, int)):
            if p >= 0:
                ebs[i].parent = ebs[p]
    finally:
        bpy.ops.object.mode_set(mode="OBJECT")
    context.view_layer.objects.active = prev_active
    return arm


def write_bone_weights(obj, names: list[str], weights, step: float = 1.0 / 1024) -> int:
    """Vertex groups named after the bones from a (V, B) sparse weight matrix (rows sum to 1).

    bpy has no bulk setter for vertex-group weights; ``VertexGroup.add`` takes a list of
    vertices with ONE weight, so weights are quantised to ``step`` and each bone gets one
    ``add`` call per distinct value (at most 1/step calls per bone; no per-vertex loop).
    Returns the number of ``add`` calls."""
    csc = weights.tocsc() if hasattr(weights, "tocsc") else weights
    calls = 0
    for b, name in enumerate(names):
        vg = obj.vertex_groups.get(name) or obj.vertex_groups.new(name=name)
        lo, hi = csc.indptr[b], csc.indptr[b + 1]
        rows = np.asarray(csc.indices[lo:hi])
        q = np.round(np.asarray(csc.data[lo:hi], float) / step).astype(np.int64)
        keep = q > 0
        rows, q = rows[keep], q[keep]
        order = np.argsort(q, kind="stable")
        rows, q = rows[order], q[order]
        vals, starts = np.unique(q, return_index=True)
        ends = np.append(starts[1:], len(q))
        for v, s, e in zip(vals, starts, ends):
            vg.add(rows[s:e].tolist(), float(v * step), "REPLACE")
            calls += 1
    return calls


def bind_armature(context, obj, arm, auto_weights: bool = False):
    """An Armature modifier on ``obj`` using ``arm``.  ``auto_weights``: Blender's own
    automatic (bone heat) weights via ``parent_set(type='ARMATURE_AUTO')``, which also parents
    the mesh to the armature and makes the modifier."""
    if auto_weights:
        for o in context.view_layer.objects:
            o.select_set(False)
        obj.select_set(True)
        arm.select_set(True)
        context.view_layer.objects.active = arm
        res = bpy.ops.object.parent_set(type="ARMATURE_AUTO")
        context.view_layer.objects.active = obj
        if "FINISHED" not in res:
            raise OsteonError("Blender's automatic weights failed (parent_set ARMATURE_AUTO)")
        return next(m for m in obj.modifiers if m.type == "ARMATURE")
    mod = obj.modifiers.new(name="Armature", type="ARMATURE")
    mod.object = arm
    return mod
