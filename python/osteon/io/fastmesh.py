"""Fast mesh parsers for the common layouts of OBJ, OFF, STL and PLY: OBJ and text numbers by
the engine's own C++ parser (``cpp/src/readers_text.cpp``, ``std::from_chars``, one pass),
binary STL / PLY as NumPy record arrays, the rest vectorised.

Why not a library: trimesh (the fallback for every layout not read here) parses OBJ in Python
line by line (~75 ms for a 13 k-face file: 94 % of a batch's time went to reading); the
well-kept compiled OBJ parsers (tinyobjloader, rapidobj) would be a second C++ dependency
for ~100 lines that only need numbers and indices, and they reorder or split vertices by
texture coordinate, which would break per-vertex weights. Here a 13 k-face OBJ takes ~2 ms. The layouts read here are the ones the tools in use write (libigl, Blender,
trimesh, RigNet, the batch's generated libraries): OBJ ``v``/``f`` lines (any ``f`` index forms
``i``, ``i/t``, ``i//n``, ``i/t/n``, negative indices, polygons fan-triangulated), OFF with
triangles or polygons, binary and ASCII STL, binary little-endian / ASCII PLY with a vertex
element and a ``vertex_indices`` list. Each function returns ``(vertices (V,3) float64, faces
(F,3) int32)`` in the file's vertex order (as ``trimesh.load(process=False,
maintain_order=True)``), or ``None`` when the file has a layout it does not take (the caller then
uses trimesh), and raises ValueError naming the problem when the file is clearly broken (an
index out of range, a count that does not match).
"""

from __future__ import annotations

import re

import numpy as np


def _numbers(chunk: bytes) -> np.ndarray | None:
    """All numbers of a whitespace-separated text chunk (the engine's C++ parser), or None if
    one is not a number."""
    from .. import _core

    values, bad = _core.parse_numbers(bytes(chunk))
    return None if bad >= 0 else values


def _fan(counts: np.ndarray, flat: np.ndarray) -> np.ndarray:
    """Fan-triangulate polygons given their corner ``counts`` and the concatenated corners."""
    if np.all(counts == 3):
        return flat.reshape(-1, 3)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    tri_per = np.maximum(counts - 2, 0)
    poly = np.repeat(np.arange(len(counts)), tri_per)
    k = np.arange(tri_per.sum()) - np.repeat(np.cumsum(tri_per) - tri_per, tri_per)
    s = starts[poly]
    return np.stack([flat[s], flat[s + k + 1], flat[s + k + 2]], axis=1)


def parse_obj(data: bytes, where: str):
    """OBJ ``v`` / ``f`` lines with the engine's C++ parser (``cpp/src/readers_text.cpp``)."""
    from .. import _core

    xyz, corners, counts, error, unsupported = _core.parse_obj(bytes(data))
    if unsupported:
        return None
    if error:
        raise ValueError(f"{where}: {error}")
    nv = len(xyz) // 3
    if not len(counts) or not nv:
        return None  # no faces or no vertices: trimesh says what it makes of it
    if corners.max() >= nv:
        raise ValueError(f"{where}: a face refers to vertex {int(corners.max()) + 1}, outside "
                         f"1..{nv}")
    return xyz.reshape(nv, 3), _fan(counts.astype(np.int64), corners)


def _strip_comments(data: bytes) -> list[bytes]:
    out = []
    for ln in data.split(b"\n"):
        ln = ln.split(b"#", 1)[0].strip()
        if ln:
            out.append(ln)
    return out


def parse_off(data: bytes, where: str):
    lines = _strip_comments(data)
    if not lines or not lines[0].startswith(b"OFF"):
        return None
    head = lines[0][3:].split()
    rest = lines[1:]
    if not head:
        if not rest:
            raise ValueError(f"{where}: OFF without the 'VERTICES FACES EDGES' line")
        head, rest = rest[0].split(), rest[1:]
    try:
        nv, nf = int(head[0]), int(head[1])
    except (ValueError, IndexError):
        raise ValueError(f"{where}: OFF counts line must be 'VERTICES FACES EDGES'") from None
    if nv < 0 or nf < 0 or len(rest) < nv + nf:
        raise ValueError(f"{where}: OFF says {nv} vertices and {nf} faces but has "
                         f"{len(rest)} data lines")
    vals = _numbers(b" ".join(rest[:nv]))
    if vals is None or len(vals) < 3 * nv:
        raise ValueError(f"{where}: OFF vertex lines must hold 3 numbers each")
    if len(vals) == 3 * nv:
        V = vals.reshape(nv, 3)
    else:
        return None  # colours per vertex: let trimesh sort them out
    fvals = _numbers(b" ".join(rest[nv:nv + nf]))
    if fvals is None or not np.all((np.abs(fvals) < 2**62) & (fvals == np.round(fvals))):
        raise ValueError(f"{where}: OFF face lines must hold integers")
    fvals = fvals.astype(np.int64)
    if len(fvals) == 4 * nf and np.all(fvals[::4] == 3):
        counts, flat = np.full(nf, 3), fvals.reshape(nf, 4)[:, 1:].ravel()
    else:
        rows = [np.array(ln.split(), dtype=np.int64) for ln in rest[nv:nv + nf]]
        if any(len(r) < 4 or r[0] < 3 or len(r) < r[0] + 1 for r in rows):
            raise ValueError(f"{where}: an OFF face line must be 'N i1 .. iN' with N >= 3")
        counts = np.array([r[0] for r in rows])
        flat = np.concatenate([r[1:r[0] + 1] for r in rows])
    if len(flat) and (flat.min() < 0 or flat.max() >= nv):
        raise ValueError(f"{where}: an OFF face refers to a vertex outside 0..{nv - 1}")
    return V, _fan(counts, flat)


def parse_stl(data: bytes, where: str):
    if len(data) >= 84:
        n = int(np.frombuffer(data, dtype="<u4", count=1, offset=80)[0])
        if len(data) == 84 + 50 * n:  # binary
            rec = np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
            tri = np.frombuffer(data, dtype=rec, count=n, offset=84)["v"]
            with np.errstate(invalid="ignore"):  # a NaN is refused by the model's checks
                V = tri.reshape(-1, 3).astype(np.float64)
            return V, np.arange(3 * n, dtype=np.int64).reshape(-1, 3)
    head = data[:512].lstrip().lower()
    if not head.startswith(b"solid"):
        return None
    if data.lower().count(b"endsolid") > 1:
        return None  # several solids: trimesh joins them
    rows = re.findall(rb"vertex\s+(\S+)\s+(\S+)\s+(\S+)", data)
    if not rows or len(rows) % 3:
        return None
    try:
        V = np.array(rows, dtype=np.float64)
    except ValueError:
        raise ValueError(f"{where}: an STL 'vertex' line holds something that is not a "
                         "number") from None
    return V, np.arange(len(V), dtype=np.int64).reshape(-1, 3)


_PLY_TYPES = {b"char": "i1", b"int8": "i1", b"uchar": "u1", b"uint8": "u1", b"short": "i2",
              b"int16": "i2", b"ushort": "u2", b"uint16": "u2", b"int": "i4", b"int32": "i4",
              b"uint": "u4", b"uint32": "u4", b"float": "f4", b"float32": "f4",
              b"double": "f8", b"float64": "f8"}


def parse_ply(data: bytes, where: str):
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        return None
    body = data[data.find(b"\n", end) + 1:]
    elements: list[list] = []
    fmt = None
    for ln in data[:end].split(b"\n")[1:]:
        t = ln.split()
        if not t or t[0] in (b"comment", b"obj_info"):
            continue
        if t[0] == b"format":
            fmt = t[1] if len(t) > 1 else None
        elif t[0] == b"element" and len(t) == 3:
            elements.append([t[1], int(t[2]), []])
        elif t[0] == b"property" and elements:
            elements[-1][2].append(t[1:])
        else:
            return None
    names = [e[0] for e in elements]
    if names[:2] != [b"vertex", b"face"] or len(names) != 2:
        return None
    (_, nv, vprops), (_, nf, fprops) = elements
    if any(len(p) != 2 or p[0] not in _PLY_TYPES for p in vprops):
        return None
    vnames = [p[1] for p in vprops]
    if vnames[:3] != [b"x", b"y", b"z"]:
        return None
    if len(fprops) != 1 or fprops[0][:1] != [b"list"] or len(fprops[0]) != 4 or \
            fprops[0][3] not in (b"vertex_indices", b"vertex_index"):
        return None
    ctype, itype = _PLY_TYPES.get(fprops[0][1]), _PLY_TYPES.get(fprops[0][2])
    if ctype is None or itype is None:
        return None
    if fmt == b"binary_little_endian":
        vdt = np.dtype([(p[1].decode(), "<" + _PLY_TYPES[p[0]]) for p in vprops])
        if len(body) < vdt.itemsize * nv:
            raise ValueError(f"{where}: PLY holds fewer bytes than its {nv} vertices need")
        vert = np.frombuffer(body, dtype=vdt, count=nv)
        V = np.stack([vert["x"], vert["y"], vert["z"]], axis=1).astype(np.float64)
        fdt = np.dtype([("n", "<" + ctype), ("i", "<" + itype, 3)])
        rest = body[vdt.itemsize * nv:]
        if len(rest) < fdt.itemsize * nf:
            return None  # polygons: trimesh
        fc = np.frombuffer(rest, dtype=fdt, count=nf)
        if not np.all(fc["n"] == 3):
            return None
        F = fc["i"].astype(np.int64)
    elif fmt == b"ascii":
        lines = body.split(b"\n")
        vals = _numbers(b" ".join(lines[:nv]))
        if vals is None or len(vals) != len(vprops) * nv:
            return None
        V = vals.reshape(nv, len(vprops))[:, :3].copy()
        for k in range(3):  # the declared precision, as a binary file would hold it
            V[:, k] = V[:, k].astype(_PLY_TYPES[vprops[k][0]]).astype(np.float64)
        fvals = _numbers(b" ".join(lines[nv:nv + nf]))
        if fvals is None or len(fvals) != 4 * nf or not np.all(fvals[::4] == 3) or \
                not np.all(np.abs(fvals) < 2**62):
            return None
        F = fvals.reshape(nf, 4)[:, 1:].astype(np.int64)
    else:
        return None
    if F.size and (F.min() < 0 or F.max() >= nv):
        raise ValueError(f"{where}: a PLY face refers to a vertex outside 0..{nv - 1}")
    return V, F


PARSERS = {".obj": parse_obj, ".off": parse_off, ".stl": parse_stl, ".ply": parse_ply}


def parse_mesh(data: bytes, ext: str, where: str):
    """``(vertices, faces)`` from the bytes of a mesh file, or None for trimesh to read it."""
    parser = PARSERS.get(ext)
    if parser is None:
        return None
    out = parser(data, where)
    if out is None:
        return None
    V, F = out
    if len(F) == 0:
        return None
    return np.ascontiguousarray(V, dtype=np.float64), np.ascontiguousarray(F, dtype=np.int32)
