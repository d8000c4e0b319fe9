"""Procedural closed test meshes (mm) with known section properties."""

from __future__ import annotations

import numpy as np


def circle(radius: float, n: int = 256) -> np.ndarray:
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.stack([radius * np.cos(t), radius * np.sin(t)], 1)


def rectangle(b: float, h: float) -> np.ndarray:
    return np.array([[-b / 2, -h / 2], [b / 2, -h / 2], [b / 2, h / 2], [-b / 2, h / 2]])


def l_section(a: float, b: float, t: float) -> np.ndarray:
    """L with legs a (along u) and b (along v), thickness t; vertex 3 is the reflex corner."""
    return np.array([[0, 0], [a, 0], [a, t], [t, t], [t, b], [0, b]], dtype=float)


def prism(profile: np.ndarray, length: float, hole: np.ndarray | None = None, fan_from: int = 0,
          stations: int = 41):
    """Closed prism along +x from x=0 to x=length with a star-shaped cross-section `profile`
    (CCW, (N,2) in the y-z plane; caps fanned from vertex `fan_from`), optionally with a `hole`
    (same vertex count as the profile, joined to it by quads). Side walls are split into
    `stations` rings so that the mesh is not one long sliver per side."""
    n = len(profile)
    xs = np.linspace(0.0, length, stations)
    rings = [np.column_stack([np.full(n, x), profile]) for x in xs]
    verts = list(rings)
    faces = []

    def side(offset_a, offset_b, flip):
        for i in range(n):
            j = (i + 1) % n
            a, b, c, d = offset_a + i, offset_a + j, offset_b + j, offset_b + i
            faces.extend([[a, c, b], [a, d, c]] if not flip else [[a, b, c], [a, c, d]])

    for k in range(stations - 1):
        side(k * n, (k + 1) * n, False)
    if hole is None:
        last = (stations - 1) * n
        for i in range(1, n - 1):
            a, b, c = fan_from, (fan_from + i) % n, (fan_from + i + 1) % n
            faces.append([a, b, c])
            faces.append([last + a, last + c, last + b])
    else:
        m = len(hole)
        assert m == n
        base = stations * n
        hole_rings = [np.column_stack([np.full(n, x), hole]) for x in xs]
        verts += hole_rings
        for k in range(stations - 1):
            side(base + k * n, base + (k + 1) * n, True)
        last, hlast = (stations - 1) * n, base + (stations - 1) * n
        for i in range(n):
            j = (i + 1) % n
            faces.extend([[i, base + i, base + j], [i, base + j, j]])
            faces.extend([[last + i, last + j, hlast + j], [last + i, hlast + j, hlast + i]])
    v = np.concatenate(verts)
    f = np.array(faces, dtype=np.int32)
    return orient_outward(v, f)


def orient_outward(v: np.ndarray, f: np.ndarray):
    """Flip all faces if the signed volume is negative."""
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    if np.einsum("ij,ij->i", a, np.cross(b, c)).sum() < 0:
        f = f[:, [0, 2, 1]]
    return v, f


def revolve(xs, radii, n: int = 96):
    """Closed surface of revolution about the x axis: radius radii[i] at x = xs[i]."""
    xs, radii = np.asarray(xs, float), np.asarray(radii, float)
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    verts = [np.column_stack([np.full(n, x), r * np.cos(t), r * np.sin(t)]) for x, r in zip(xs, radii)]
    faces = []
    for k in range(len(xs) - 1):
        for i in range(n):
            j = (i + 1) % n
            a, b, c, d = k * n + i, k * n + j, (k + 1) * n + j, (k + 1) * n + i
            faces.extend([[a, b, c], [a, c, d]])
    v = np.concatenate(verts + [np.array([[xs[0], 0, 0], [xs[-1], 0, 0]])])
    c0, c1 = len(v) - 2, len(v) - 1
    last = (len(xs) - 1) * n
    for i in range(n):
        j = (i + 1) % n
        faces.append([c0, j, i])
        faces.append([c1, last + i, last + j])
    return orient_outward(v, np.array(faces, dtype=np.int32))


def _revolve_along(start, end, xs_of_length, radii, n: int):
    """`revolve` a profile along the segment `start` -> `end` (3D points): xs_of_length(L) gives
    the profile's stations (mm along the axis from `start`), radii their radii."""
    start, end = np.asarray(start, float), np.asarray(end, float)
    axis = end - start
    length = np.linalg.norm(axis)
    v, f = revolve(xs_of_length(length), radii, n)
    x = axis / length
    helper = np.array([0.0, 0.0, 1.0]) if abs(x[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    y = np.cross(helper, x)
    y /= np.linalg.norm(y)
    z = np.cross(x, y)
    return start + v @ np.stack([x, y, z]), f


def cylinder_along(start, end, radius: float, n: int = 48, stations: int = 24):
    """Closed cylinder from `start` to `end` (3D points)."""
    return _revolve_along(start, end, lambda length: np.linspace(0, length, stations),
                          np.full(stations, radius), n)


def capsule_along(start, end, r: float, n: int = 64, cap_stations: int = 12, stations: int = 24):
    """Closed capsule (cylinder with hemispherical ends) of radius r from `start` to `end`."""
    t = np.linspace(0, np.pi / 2, cap_stations, endpoint=False)[1:]
    radii = np.concatenate([r * np.sin(t), np.full(stations, r), r * np.cos(t)])
    return _revolve_along(
        start, end,
        lambda length: np.concatenate([-r * np.cos(t), np.linspace(0, length, stations),
                                       length + r * np.sin(t)]),
        radii, n)


def merge(*meshes):
    """Disjoint union of meshes."""
    vs, fs, off = [], [], 0
    for v, f in meshes:
        vs.append(v)
        fs.append(f + off)
        off += len(v)
    return np.concatenate(vs), np.concatenate(fs).astype(np.int32)


def torus(R: float = 30.0, r: float = 8.0, n: int = 48, m: int = 16):
    """Closed torus about z (ring radius R, tube radius r, mm): n x m quads, 2 n m triangles,
    outward normals."""
    u = np.linspace(0, 2 * np.pi, n, endpoint=False)
    w = np.linspace(0, 2 * np.pi, m, endpoint=False)
    U, W = np.meshgrid(u, w, indexing="ij")
    v = np.column_stack([((R + r * np.cos(W)) * np.cos(U)).ravel(),
                         ((R + r * np.cos(W)) * np.sin(U)).ravel(), (r * np.sin(W)).ravel()])
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    a, b = i * m + j, ((i + 1) % n) * m + j
    c, d = ((i + 1) % n) * m + (j + 1) % m, i * m + (j + 1) % m
    f = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3),
                        np.stack([a, c, d], -1).reshape(-1, 3)])
    return v, f.astype(np.int32)
