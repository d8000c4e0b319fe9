"""Skinned glTF 2.0 (``.gltf`` / ``.glb``) via pygltflib.

Reads the first skin and every triangle primitive of the mesh nodes using it, in bind space
(the mesh's own coordinates, which is where the skin's inverse bind matrices put the joints:
joint j sits at ``inverse(IBM_j) · (0,0,0,1)``). ``JOINTS_n``/``WEIGHTS_n`` give per-joint
weights; the joint tree (nearest ancestor node that is a joint of the skin) becomes bones as in
:func:`osteon.io.model.bones_from_joint_tree` (a joint's weight drives the bone leaving it, the
way Blender imports glTF skins). Vertices at the same position are welded, so unindexed,
flat-shaded files (e.g. Khronos Fox.glb) become closed meshes.
"""

from __future__ import annotations

import base64
import os

import numpy as np

from .model import bones_from_joint_tree, joint_weights_to_bones

_CT = {
    5120: np.int8,
    5121: np.uint8,
    5122: np.int16,
    5123: np.uint16,
    5125: np.uint32,
    5126: np.float32,
}
_NC = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}


class _Reader:
    def __init__(self, path):
        import pygltflib

        self.path = os.fspath(path)
        try:
            self.g = pygltflib.GLTF2().load(self.path)
        except Exception as e:  # noqa: BLE001 - pygltflib raises many kinds
            raise ValueError(f"{self.path}: cannot read glTF ({type(e).__name__}: {e})") from None
        if self.g is None:
            raise ValueError(f"{self.path}: cannot read glTF")
        self._buffers = {}

    def buffer(self, i):
        if i not in self._buffers:
            b = self.g.buffers[i]
            if b.uri is None:
                data = self.g.binary_blob()
            elif b.uri.startswith("data:"):
                data = base64.b64decode(b.uri.split(",", 1)[1])
            else:
                with open(os.path.join(os.path.dirname(self.path), b.uri), "rb") as f:
                    data = f.read()
            if data is None:
                raise ValueError(f"{self.path}: glTF buffer {i} has no data")
            self._buffers[i] = data
        return self._buffers[i]

    def accessor(self, i):
        a = self.g.accessors[i]
        dt = np.dtype(_CT[a.componentType]).newbyteorder("<")
        nc = _NC[a.type]
        out = np.zeros((a.count, nc), dtype=dt)
        if a.bufferView is not None:
            bv = self.g.bufferViews[a.bufferView]
            data = self.buffer(bv.buffer)
            start = (bv.byteOffset or 0) + (a.byteOffset or 0)
            item = dt.itemsize * nc
            stride = bv.byteStride or item
            if stride == item:
                out = np.frombuffer(data, dtype=dt, count=a.count * nc, offset=start)
                out = out.reshape(a.count, nc).copy()
            else:
                raw = np.frombuffer(
                    data, dtype=np.uint8, count=stride * (a.count - 1) + item, offset=start
                )
                idx = np.arange(a.count)[:, None] * stride + np.arange(item)[None, :]
                out = raw[idx].copy().view(dt).reshape(a.count, nc)
        if a.sparse is not None:
            raise ValueError(f"{self.path}: sparse glTF accessors are not supported")
        res = out.astype(np.float64)
        if a.normalized:
            if dt.kind == "u":
                res /= np.iinfo(dt).max
            elif dt.kind == "i":
                res = np.maximum(res / np.iinfo(dt).max, -1.0)
        return res if nc > 1 else res.ravel()


def _node_matrix(n):
    if n.matrix is not None:
        return np.asarray(n.matrix, dtype=np.float64).reshape(4, 4).T
    M = np.eye(4)
    if n.scale is not None:
        M = np.diag([*n.scale, 1.0]) @ M
    if n.rotation is not None:
        x, y, z, w = n.rotation
        R = np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
            ]
        )
        T = np.eye(4)
        T[:3, :3] = R
        M = T @ M
    if n.translation is not None:
        T = np.eye(4)
        T[:3, 3] = n.translation
        M = T @ M
    return M


def _triangles(idx, mode):
    if mode in (None, 4):
        return idx.reshape(-1, 3)
    if mode == 5:  # strip
        t = np.stack([idx[:-2], idx[1:-1], idx[2:]], axis=1)
        t[1::2] = t[1::2][:, [1, 0, 2]]
        return t
    if mode == 6:  # fan
        return np.stack([np.full(len(idx) - 2, idx[0]), idx[1:-1], idx[2:]], axis=1)
    return np.zeros((0, 3), dtype=np.int64)


def weld(vertices, faces, rel_tol=1e-9):
    """Merge vertices closer than ``rel_tol`` × bounding-box diagonal; returns
    ``(new_vertices, new_faces, old_to_new)``; faces that collapse are removed."""
    diag = float(np.linalg.norm(vertices.max(0) - vertices.min(0))) or 1.0
    q = np.round((vertices - vertices.min(0)) / (rel_tol * diag)).astype(np.int64)
    _, first, inv = np.unique(q, axis=0, return_index=True, return_inverse=True)
    inv = inv.ravel()
    order = np.argsort(first)  # keep the first-seen order
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    old_to_new = rank[inv]
    newv = vertices[first[order]]
    f = old_to_new[faces]
    ok = (f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2])
    return newv, f[ok], old_to_new


def read_gltf(path):
    """Read a skinned glTF/GLB → ``(vertices, faces, heads, tails, parents, names, weights)``."""
    j = read_gltf_joints(path)
    V, F, rows, jidx, vals = j["vertices"], j["faces"], j["skin_rows"], j["skin_joints"], \
        j["skin_values"]
    jpos, jparent, names = j["positions"], j["parent"], j["names"]
    heads, tails, parents, bnames, targets = bones_from_joint_tree(jpos, jparent, names)
    if len(heads) == 0:
        raise ValueError(f"{path}: the glTF skin has no bones of non-zero length")
    # weld: weights of merged vertices are averaged (they are equal in valid files)
    Vw, Fw, o2n = weld(V, F)
    W = joint_weights_to_bones(V, rows, jidx, vals, targets, heads, tails, names)
    import scipy.sparse as sp

    from .model import drop_unweighted_roots, normalize_rows

    M = sp.csr_matrix((np.ones(len(V)), (o2n, np.arange(len(V)))), shape=(len(Vw), len(V)))
    W = normalize_rows(M @ W)
    heads, tails, parents, bnames, W, _ = drop_unweighted_roots(heads, tails, parents, bnames, W)
    return Vw, Fw, heads, tails, parents, bnames, W


def read_gltf_joints(path) -> dict:
    """The joint rig of a skinned glTF/GLB as stored: ``vertices`` (V, 3), ``faces`` (F, 3)
    (not welded), joint ``names``, ``positions`` (J, 3) in bind space, ``parent`` (J,) and the
    skin as triplets ``skin_rows``, ``skin_joints``, ``skin_values`` (what Blender's importer
    turns into one bone and one vertex group per joint)."""
    r = _Reader(path)
    g = r.g
    if not g.skins:
        raise ValueError(f"{r.path}: glTF has no skin (no skeleton to analyse)")
    skin_i = 0
    skin = g.skins[skin_i]
    joints = list(skin.joints)
    nodes = [i for i, n in enumerate(g.nodes) if n.mesh is not None and n.skin == skin_i]
    if not nodes:
        raise ValueError(f"{r.path}: no mesh node uses the glTF skin")
    verts, faces, wr, wj, wv = [], [], [], [], []
    off = 0
    for ni in nodes:
        for prim in g.meshes[g.nodes[ni].mesh].primitives:
            if prim.mode not in (None, 4, 5, 6):
                continue
            at = prim.attributes
            pos = r.accessor(at.POSITION)
            n = len(pos)
            idx = (
                r.accessor(prim.indices).astype(np.int64)
                if prim.indices is not None
                else np.arange(n)
            )
            faces.append(_triangles(idx, prim.mode) + off)
            verts.append(pos)
            for k in range(4):
                ja = getattr(at, f"JOINTS_{k}", None)
                wa = getattr(at, f"WEIGHTS_{k}", None)
                if ja is None or wa is None:
                    break
                jj = r.accessor(ja).astype(np.int64)
                ww = r.accessor(wa)
                nz = ww > 0
                rows = np.broadcast_to(np.arange(n)[:, None], jj.shape)[nz] + off
                wr.append(rows)
                wj.append(jj[nz])
                wv.append(ww[nz])
            off += n
    if not verts:
        raise ValueError(f"{r.path}: the skinned mesh has no triangle primitives")
    V = np.concatenate(verts)
    F = np.concatenate(faces)
    rows = np.concatenate(wr) if wr else np.zeros(0, np.int64)
    jidx = np.concatenate(wj) if wj else np.zeros(0, np.int64)
    vals = np.concatenate(wv) if wv else np.zeros(0)
    if len(jidx) and (jidx.min() < 0 or jidx.max() >= len(joints)):
        raise ValueError(f"{r.path}: JOINTS_0 index outside the skin's {len(joints)} joints")
    # joints in bind space
    if skin.inverseBindMatrices is not None:
        ibm = r.accessor(skin.inverseBindMatrices).reshape(-1, 4, 4).transpose(0, 2, 1)
        jpos = np.array([np.linalg.inv(m)[:3, 3] for m in ibm])
    else:  # identity IBMs: joints at their world positions
        parent_node = {c: i for i, n in enumerate(g.nodes) for c in (n.children or [])}

        def world(i):
            M = _node_matrix(g.nodes[i])
            while i in parent_node:
                i = parent_node[i]
                M = _node_matrix(g.nodes[i]) @ M
            return M

        jpos = np.array([world(j)[:3, 3] for j in joints])
    parent_node = {c: i for i, n in enumerate(g.nodes) for c in (n.children or [])}
    jset = {n: k for k, n in enumerate(joints)}
    jparent = np.full(len(joints), -1, dtype=np.int64)
    for k, n in enumerate(joints):
        p = parent_node.get(n)
        while p is not None and p not in jset:
            p = parent_node.get(p)
        if p is not None:
            jparent[k] = jset[p]
    names = [g.nodes[n].name or f"joint_{k}" for k, n in enumerate(joints)]
    return {"vertices": V, "faces": F, "names": names, "positions": jpos, "parent": jparent,
            "skin_rows": rows, "skin_joints": jidx, "skin_values": vals}
