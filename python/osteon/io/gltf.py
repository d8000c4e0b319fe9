"""Skinned glTF 2.0 (``.gltf`` / ``.glb``), read from its JSON directly (pygltflib's
dataclass conversion took 1.3 s of Fox.glb's 1.3 s read).

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
import json
import os
import struct

import numpy as np

from .model import bones_from_joint_tree, check_tree, joint_weights_to_bones

_CT = {
    5120: np.int8,
    5121: np.uint8,
    5122: np.int16,
    5123: np.uint16,
    5125: np.uint32,
    5126: np.float32,
}
#: most items of an accessor without a buffer view (all zeros; a guard against a count that
#: would allocate gigabytes for nothing)
_MAX_ZERO_ITEMS = 50_000_000
_NC = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}


class _Obj:
    """A glTF JSON object with attribute access (``node.mesh``; None when absent), the names
    of the glTF schema (those pygltflib used). Lists of objects come back as lists of _Obj."""

    __slots__ = ("_c", "_d")

    def __init__(self, d: dict):
        self._d = d
        self._c = {}

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        if name not in self._c:  # converted once: lists of nodes are indexed in loops
            v = self._d.get(name)
            if isinstance(v, dict):
                v = _Obj(v)
            elif isinstance(v, list):
                v = [_Obj(x) if isinstance(x, dict) else x for x in v]
            self._c[name] = v
        return self._c[name]


def _glb_chunks(raw: bytes, path: str) -> tuple[bytes, bytes | None]:
    """The JSON and BIN chunks of a GLB file (glTF 2.0 binary container)."""
    if len(raw) < 20:
        raise ValueError(f"{path}: GLB file shorter than its headers")
    _, version, length = struct.unpack_from("<4sII", raw, 0)
    if version != 2:
        raise ValueError(f"{path}: GLB version {version}; only glTF 2.0 is read")
    end = min(length, len(raw))
    chunks, off = {}, 12
    while off + 8 <= end:
        size, kind = struct.unpack_from("<II", raw, off)
        if off + 8 + size > end:
            raise ValueError(f"{path}: GLB chunk at byte {off} runs past the file's end")
        chunks.setdefault(kind, raw[off + 8:off + 8 + size])
        off += 8 + size
    if 0x4E4F534A not in chunks:
        raise ValueError(f"{path}: GLB without a JSON chunk")
    return chunks[0x4E4F534A], chunks.get(0x004E4942)


class _Reader:
    """A glTF document with checked look-ups: every index, type and byte range is checked
    before it is used; a problem is a ValueError naming the file and the item."""

    def __init__(self, path):
        self.path = os.fspath(path)
        try:
            with open(self.path, "rb") as fh:
                raw = fh.read()
        except OSError as e:
            raise ValueError(f"{self.path}: cannot read ({e.strerror or e})") from None
        self.blob = None
        if raw[:4] == b"glTF":
            text, self.blob = _glb_chunks(raw, self.path)
        else:
            text = raw
        try:
            doc = json.loads(text)
        except (ValueError, RecursionError) as e:
            raise ValueError(f"{self.path}: not glTF JSON ({type(e).__name__}: "
                             f"{str(e)[:80]})") from None
        if not isinstance(doc, dict):
            raise ValueError(f"{self.path}: not a glTF document (top level is not an object)")  # noqa: TRY004
        self.g = _Obj(doc)
        for kind in ("accessors", "bufferViews", "buffers", "meshes", "nodes", "skins"):
            items = getattr(self.g, kind)
            if items is not None and not isinstance(items, list):
                raise ValueError(f"{self.path}: '{kind}' is not a list")
            for k, x in enumerate(items or []):
                if not isinstance(x, _Obj):
                    raise ValueError(f"{self.path}: {kind}[{k}] is not a glTF object "  # noqa: TRY004
                                     f"({type(x).__name__})")
        self._buffers = {}

    def item(self, kind: str, i, owner: str = ""):
        """``self.g.<kind>[i]`` with ``i`` checked (an int inside the list)."""
        items = getattr(self.g, kind) or []
        if isinstance(i, bool) or not isinstance(i, int) or not 0 <= i < len(items):
            where = f" ({owner})" if owner else ""
            raise ValueError(f"{self.path}: {kind} index {i!r}{where} outside the file's "
                             f"{len(items)} {kind}")
        return items[i]

    def buffer(self, i):
        self.item("buffers", i)
        if i not in self._buffers:
            b = self.item("buffers", i)
            if b.uri is not None and not isinstance(b.uri, str):
                raise ValueError(f"{self.path}: glTF buffer {i}: uri is not a string")
            if b.uri is None:
                data = self.blob
            elif b.uri.startswith("data:"):
                try:
                    data = base64.b64decode(b.uri.split(",", 1)[1])
                except (ValueError, IndexError) as e:
                    raise ValueError(f"{self.path}: glTF buffer {i}: bad data URI ({e})") from None
            else:
                f = os.path.join(os.path.dirname(self.path), b.uri)
                if not os.path.isfile(f):
                    raise ValueError(f"{self.path}: glTF buffer {i}: {b.uri!r} is not a file")
                try:
                    with open(f, "rb") as fh:
                        data = fh.read()
                except OSError as e:
                    raise ValueError(f"{self.path}: glTF buffer {i}: cannot read {b.uri!r} "
                                     f"({e.strerror or e})") from None
            if data is None:
                raise ValueError(f"{self.path}: glTF buffer {i} has no data")
            self._buffers[i] = data
        return self._buffers[i]

    def accessor(self, i, owner: str = ""):
        a = self.item("accessors", i, owner)
        what = f"{self.path}: accessor {i}"
        if not isinstance(a.componentType, int) or a.componentType not in _CT:
            raise ValueError(f"{what}: unknown componentType {a.componentType!r} "
                             f"(known: {', '.join(map(str, _CT))})")
        if not isinstance(a.type, str) or a.type not in _NC:
            raise ValueError(f"{what}: unknown type {a.type!r}")
        if not isinstance(a.count, int) or a.count < 0:
            raise ValueError(f"{what}: count {a.count!r} is not a non-negative integer")
        if a.sparse is not None:
            raise ValueError(f"{what}: sparse glTF accessors are not supported")
        dt = np.dtype(_CT[a.componentType]).newbyteorder("<")
        nc = _NC[a.type]
        if a.bufferView is None and a.count > _MAX_ZERO_ITEMS:  # all zeros, and absurd
            raise ValueError(f"{what}: {a.count} items without a buffer view")
        out = np.zeros((a.count if a.bufferView is None else 0, nc), dtype=dt)
        if a.bufferView is not None and a.count:
            bv = self.item("bufferViews", a.bufferView, f"of accessor {i}")
            data = self.buffer(bv.buffer)
            view_off = _count(bv.byteOffset, f"{what}: its buffer view's byteOffset")
            start = view_off + _count(a.byteOffset, f"{what}: byteOffset")
            item = dt.itemsize * nc
            stride = _count(bv.byteStride, f"{what}: its buffer view's byteStride") or item
            need = start + stride * (a.count - 1) + item
            end = view_off + _count(bv.byteLength, f"{what}: its buffer view's byteLength")
            if start < 0 or stride < item or need > len(data) or need > end:
                raise ValueError(f"{what}: {a.count} x {a.type} from byte {start} (stride "
                                 f"{stride}) runs past its buffer view / buffer of "
                                 f"{min(len(data), end)} bytes")
            if stride == item:
                out = np.frombuffer(data, dtype=dt, count=a.count * nc, offset=start)
                out = out.reshape(a.count, nc).copy()
            else:
                raw = np.frombuffer(data, dtype=np.uint8, count=need - start, offset=start)
                idx = np.arange(a.count)[:, None] * stride + np.arange(item)[None, :]
                out = raw[idx].copy().view(dt).reshape(a.count, nc)
        res = out.astype(np.float64)
        if a.normalized:
            if dt.kind == "u":
                res /= np.iinfo(dt).max
            elif dt.kind == "i":
                res = np.maximum(res / np.iinfo(dt).max, -1.0)
        return res if nc > 1 else res.ravel()

    def node_parents(self) -> np.ndarray:
        """Parent node of every node (-1 = none), checked: children in range, one parent per
        node, no cycle."""
        nodes = self.g.nodes or []
        parent = np.full(len(nodes), -1, dtype=np.int64)
        for i, n in enumerate(nodes):
            if n.children is not None and not isinstance(n.children, list):
                raise ValueError(f"{self.path}: node {i}'s children is not a list")
            for c in n.children or []:
                self.item("nodes", c, f"a child of node {i}")
                if parent[c] >= 0 and parent[c] != i:
                    raise ValueError(f"{self.path}: node {c} is a child of nodes "
                                     f"{int(parent[c])} and {i}; not a tree")
                parent[c] = i
        names = [n.name if isinstance(n.name, str) and n.name else f"node {k}"
                 for k, n in enumerate(nodes)]
        check_tree(parent, self.path, "glTF node", names)
        return parent


def _count(x, what: str) -> int:
    """A byte offset / length / stride of the file: an integer >= 0 (0 when absent)."""
    if x is None:
        return 0
    if isinstance(x, bool) or not isinstance(x, int) or x < 0:
        raise ValueError(f"{what} is {x!r}, not an integer >= 0")
    return x


def _numbers_of(n, key: str, size: int, where: str):
    v = getattr(n, key)
    if v is None:
        return None
    try:
        a = np.asarray(v, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        a = np.zeros(0)
    if a.size != size or not np.all(np.isfinite(a)):
        raise ValueError(f"{where}: node {key} must be {size} finite numbers")
    return a


def _node_matrix(n, where: str = "glTF"):
    """The node's local transform (4x4), checked: matrix 16, rotation 4, scale and
    translation 3 finite numbers."""
    m = _numbers_of(n, "matrix", 16, where)
    if m is not None:
        return m.reshape(4, 4).T
    scale = _numbers_of(n, "scale", 3, where)
    rot = _numbers_of(n, "rotation", 4, where)
    trans = _numbers_of(n, "translation", 3, where)
    return _trs(scale, rot, trans)


def _trs(scale, rotation, translation):
    M = np.eye(4)
    if scale is not None:
        M = np.diag([*scale, 1.0]) @ M
    if rotation is not None:
        x, y, z, w = rotation
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
    if translation is not None:
        T = np.eye(4)
        T[:3, 3] = translation
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


def read_gltf(path, info: dict | None = None):
    """Read a skinned glTF/GLB → ``(vertices, faces, heads, tails, parents, names, weights)``.

    ``info`` (a dict, optional) receives ``warnings``, ``findings`` and ``notes`` as in
    :func:`osteon.io.rignet.rignet_skeleton`; a skin without weights keeps all its bones and
    returns ``None`` weights, with a warning."""
    import scipy.sparse as sp

    from .model import (
        clean_weights,
        finish_joint_rig,
        normalize_rows,
    )

    info = {} if info is None else info
    info.setdefault("warnings", [])
    info.setdefault("notes", [])
    j = read_gltf_joints(path)
    V, F, rows, jidx, vals = j["vertices"], j["faces"], j["skin_rows"], j["skin_joints"], \
        j["skin_values"]
    jpos, jparent, names = j["positions"], j["parent"], j["names"]
    heads, tails, parents, bnames, targets = bones_from_joint_tree(jpos, jparent, names)
    if len(heads) == 0:
        raise ValueError(f"{path}: the glTF skin has no bones of non-zero length")
    # weld: weights of merged vertices are averaged (they are equal in valid files)
    Vw, Fw, o2n = weld(V, F)
    if len(rows) == 0:
        info["warnings"].append(
            f"{path}: the skin has no weights (no JOINTS_0/WEIGHTS_0 with a positive value): "
            f"no weights for its {len(heads)} bones; each vertex follows its nearest bone")
        return Vw, Fw, heads, tails, parents, bnames, None
    found, warns = clean_weights(rows, vals, len(V), str(path))
    found["nonfinite"] += j["bad_weights"][0]
    found["negative"] += j["bad_weights"][1]
    from .model import weight_warnings

    info["findings"] = found
    info["warnings"].extend(weight_warnings(found, str(path)) if any(j["bad_weights"])
                            else warns)
    W = joint_weights_to_bones(V, rows, jidx, vals, targets, heads, tails, names)
    M = sp.csr_matrix((np.ones(len(V)), (o2n, np.arange(len(V)))), shape=(len(Vw), len(V)))
    W = normalize_rows(M @ W)
    heads, tails, parents, bnames, W = finish_joint_rig(heads, tails, parents, bnames, W, info,
                                                        str(path))
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
    if not isinstance(skin, _Obj):
        raise ValueError(f"{r.path}: skins[0] is not a glTF object")  # noqa: TRY004
    if skin.joints is not None and not isinstance(skin.joints, list):
        raise ValueError(f"{r.path}: skin 0's joints is not a list")
    joints = list(skin.joints or [])
    for k, n in enumerate(joints):
        r.item("nodes", n, f"joint {k} of skin 0")
    if len(set(joints)) != len(joints):
        raise ValueError(f"{r.path}: skin 0 lists a node twice among its joints")
    nodes = [i for i, n in enumerate(g.nodes) if n.mesh is not None and n.skin == skin_i]
    if not nodes:
        raise ValueError(f"{r.path}: no mesh node uses the glTF skin")
    node_parent = r.node_parents()  # checked before any walk up the node tree
    verts, faces, wr, wj, wv = [], [], [], [], []
    off = 0
    bad_weights = [0, 0]  # NaN/inf, negative entries (dropped)
    for ni in nodes:
        mesh = r.item("meshes", g.nodes[ni].mesh, f"of node {ni}")
        if mesh.primitives is not None and not isinstance(mesh.primitives, list):
            raise ValueError(f"{r.path}: mesh {g.nodes[ni].mesh}'s primitives is not a list")
        for prim in mesh.primitives or []:
            if not isinstance(prim, _Obj) or not isinstance(prim.attributes, (_Obj, type(None))):
                raise ValueError(f"{r.path}: a primitive of mesh {g.nodes[ni].mesh} is not a "  # noqa: TRY004
                                 "glTF object")
            if prim.mode not in (None, 4, 5, 6):
                continue
            at = prim.attributes
            if at is None or at.POSITION is None:
                raise ValueError(f"{r.path}: a primitive of mesh {g.nodes[ni].mesh} has no "
                                 "POSITION")
            pos = r.accessor(at.POSITION, "POSITION")
            if pos.ndim != 2 or pos.shape[1] != 3:
                raise ValueError(f"{r.path}: POSITION accessor {at.POSITION} is not VEC3")
            n = len(pos)
            idx = (
                r.accessor(prim.indices, "indices").astype(np.int64)
                if prim.indices is not None
                else np.arange(n)
            )
            if idx.ndim != 1 or (len(idx) and (idx.min() < 0 or idx.max() >= n)):
                raise ValueError(f"{r.path}: indices accessor {prim.indices} refers to vertices "
                                 f"outside the primitive's {n}")
            if (prim.mode in (None, 4) and len(idx) % 3) or len(idx) < 3:
                raise ValueError(f"{r.path}: indices accessor {prim.indices} holds {len(idx)} "
                                 "indices, not whole triangles")
            faces.append(_triangles(idx, prim.mode) + off)
            verts.append(pos)
            for k in range(4):
                ja = getattr(at, f"JOINTS_{k}", None)
                wa = getattr(at, f"WEIGHTS_{k}", None)
                if ja is None or wa is None:
                    break
                jj = r.accessor(ja, f"JOINTS_{k}")
                ww = r.accessor(wa, f"WEIGHTS_{k}")
                jj = jj.reshape(n, -1) if jj.size == ww.size and jj.size % max(n, 1) == 0 \
                    else None
                if jj is None or ww.shape[0] != n:
                    raise ValueError(f"{r.path}: JOINTS_{k} / WEIGHTS_{k} do not hold one row "
                                     f"per vertex ({n})")
                ww = ww.reshape(n, -1)
                bad_weights[0] += int(np.count_nonzero(~np.isfinite(ww)))
                bad_weights[1] += int(np.count_nonzero(ww < 0))
                nz = ww > 0
                jn = jj[nz]
                if len(jn) and not (np.all(np.isfinite(jn)) and jn.min() >= 0
                                    and jn.max() < len(joints)):
                    raise ValueError(f"{r.path}: JOINTS_{k} index outside the skin's "
                                     f"{len(joints)} joints")
                rows = np.broadcast_to(np.arange(n)[:, None], jj.shape)[nz] + off
                wr.append(rows)
                wj.append(jn.astype(np.int64))
                wv.append(ww[nz])
            off += n
    if not verts:
        raise ValueError(f"{r.path}: the skinned mesh has no triangle primitives")
    V = np.concatenate(verts)
    F = np.concatenate(faces)
    rows = np.concatenate(wr) if wr else np.zeros(0, np.int64)
    jidx = np.concatenate(wj) if wj else np.zeros(0, np.int64)
    vals = np.concatenate(wv) if wv else np.zeros(0)
    # joints in bind space
    if skin.inverseBindMatrices is not None:
        ibm = r.accessor(skin.inverseBindMatrices, "inverseBindMatrices")
        if ibm.size != 16 * len(joints):
            raise ValueError(f"{r.path}: inverseBindMatrices holds {ibm.size // 16} matrices "
                             f"for {len(joints)} joints")
        ibm = ibm.reshape(-1, 4, 4).transpose(0, 2, 1)
        try:
            jpos = np.linalg.inv(ibm)[:, :3, 3]
        except np.linalg.LinAlgError:
            bad = [k for k, m in enumerate(ibm) if abs(np.linalg.det(m)) < 1e-300]
            raise ValueError(f"{r.path}: the inverse bind matrix of joint "
                             f"{bad[0] if bad else '?'} cannot be inverted (singular)") from None
    else:  # identity IBMs: joints at their world positions

        def world(i):
            M = _node_matrix(g.nodes[i], r.path)
            while node_parent[i] >= 0:
                i = int(node_parent[i])
                M = _node_matrix(g.nodes[i], r.path) @ M
            return M

        jpos = np.array([world(j)[:3, 3] for j in joints]).reshape(-1, 3)
    jset = {n: k for k, n in enumerate(joints)}
    jparent = np.full(len(joints), -1, dtype=np.int64)
    for k, n in enumerate(joints):
        p = int(node_parent[n])
        while p >= 0 and p not in jset:
            p = int(node_parent[p])
        if p >= 0:
            jparent[k] = jset[p]
    if not np.all(np.isfinite(jpos)):
        raise ValueError(f"{r.path}: joint positions contain NaN or inf")
    names = [g.nodes[n].name if isinstance(g.nodes[n].name, str) and g.nodes[n].name
             else f"joint_{k}" for k, n in enumerate(joints)]
    return {"vertices": V, "faces": F, "names": names, "positions": jpos, "parent": jparent,
            "skin_rows": rows, "skin_joints": jidx, "skin_values": vals,
            "bad_weights": bad_weights}
