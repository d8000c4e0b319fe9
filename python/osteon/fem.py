"""FEM cross-check of osteon's section stresses with gmsh (tet mesh) and CalculiX (``ccx``).

Pipeline (:func:`cross_check`):

1. tet-mesh the closed surface with the ``gmsh`` binary (surface re-meshed at ``mesh_size`` mm,
   quadratic 10-node tetrahedra, mid-side nodes on straight edges);
2. hold the root region: every node within ``hold_radius`` mm of the held point is fixed;
3. for every distinct load point of the tested sections, three unit load cases (x, y, z), the
   force spread evenly over the surface nodes within one element size of the point;
4. solve linear elasticity with ``ccx`` (E and ν do not change the stress of this statically
   determinate load case much; defaults are PLA-like, 3500 MPa and 0.35), read the nodal
   stresses (extrapolated, averaged) from the ``.frd`` file;
5. for each section plane, cut the tetrahedra of the body part around the section centre by the
   plane, interpolate the stress tensor to the cut points and take σ_nn = nᵀσn. With the three
   unit cases, σ_nn at a point is a linear function g·f of the force vector f, so the worst
   normal stress over all force directions of magnitude F is ``F · max_p |g_p|``. That is the FEM
   counterpart of osteon's worst case (``F·d / W`` with W the minimum over bending directions).

Units: mm, N, MPa.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass, field

import numpy as np

# gmsh 10-node tet: 0-3 corners, 4:(0,1) 5:(1,2) 6:(0,2) 7:(0,3) 8:(2,3) 9:(1,3)
# CalculiX C3D10:   0-3 corners, 4:(0,1) 5:(1,2) 6:(2,0) 7:(0,3) 8:(1,3) 9:(2,3)
_GMSH_TO_CCX = [0, 1, 2, 3, 4, 5, 6, 7, 9, 8]
# (corner a, mid node, corner b) in CalculiX order
_TET_EDGES = [(0, 4, 1), (1, 5, 2), (2, 6, 0), (0, 7, 3), (1, 8, 3), (2, 9, 3)]


def find_tools() -> dict:
    """Paths of the external programs: ``{'gmsh': path or None, 'ccx': path or None}``."""
    return {
        "gmsh": os.environ.get("OSTEON_GMSH") or shutil.which("gmsh"),
        "ccx": os.environ.get("OSTEON_CCX") or shutil.which("ccx"),
    }


def _require_tools():
    t = find_tools()
    missing = [k for k, v in t.items() if v is None]
    if missing:
        raise RuntimeError(
            "FEM cross-check needs the programs "
            + " and ".join(missing)
            + " (Debian/Ubuntu: apt-get install gmsh calculix-ccx)"
        )
    return t


# ----------------------------------------------------------------------------- meshing


def tet_mesh(vertices, faces, mesh_size, workdir, threads=2, timeout=600, refine=(), remesh=True):
    """Quadratic tet mesh of a closed triangle surface → ``(nodes (N,3), tets (T,10))``,
    tets in CalculiX C3D10 node order, 0-based.

    ``mesh_size`` mm is the element size away from the refined regions; ``refine`` is a list of
    ``(center (3,), radius mm, size mm)`` balls meshed finer (the tested sections).
    ``remesh=False`` keeps the given surface triangles (only the interior is meshed; sizes grow
    from the surface up to ``mesh_size``).
    """
    import trimesh

    tools = _require_tools()
    m = trimesh.Trimesh(np.asarray(vertices, float), np.asarray(faces), process=True)
    if not m.is_watertight:
        raise ValueError("FEM needs a closed (watertight) surface; this mesh has open edges")
    stl = os.path.join(workdir, "surface.stl")
    m.export(stl)
    geo = os.path.join(workdir, "mesh.geo")
    msh = os.path.join(workdir, "mesh.msh")
    with open(geo, "w") as f:
        f.write(
            f'Merge "{stl}";\n'
            + (
                "ClassifySurfaces{40*Pi/180, 1, 1, Pi};\nCreateGeometry;\n"
                "Surface Loop(1) = Surface{:};\n"
                if remesh
                else "Surface Loop(1) = {1};\n"
            )
            + "Volume(1) = {1};\n"
            "Physical Volume(1) = {1};\n"
            f"Mesh.CharacteristicLengthMax = {float(mesh_size)};\n"
            "Mesh.CharacteristicLengthFromCurvature = 0;\n"
            "Mesh.CharacteristicLengthFromPoints = 0;\n"
            f"Mesh.CharacteristicLengthExtendFromBoundary = {0 if remesh else 1};\n"
            "Mesh.ElementOrder = 2;\n"
            "Mesh.SecondOrderLinear = 1;\n"
            "Mesh.MshFileVersion = 2.2;\n"
            "Mesh.Algorithm = 6;\n"
            "Mesh.Algorithm3D = 1;\n"
            "Mesh.Optimize = 1;\n"
        )
        ids = []
        for k, (c, r, h) in enumerate(refine, start=1):
            f.write(
                f"Field[{k}] = Ball;\nField[{k}].Radius = {float(r)};\n"
                f"Field[{k}].Thickness = {float(r)};\n"
                f"Field[{k}].VIn = {float(h)};\nField[{k}].VOut = {float(mesh_size)};\n"
                f"Field[{k}].XCenter = {c[0]:.9g};\nField[{k}].YCenter = {c[1]:.9g};\n"
                f"Field[{k}].ZCenter = {c[2]:.9g};\n"
            )
            ids.append(k)
        if ids:
            m_id = len(ids) + 1
            f.write(
                f"Field[{m_id}] = Min;\nField[{m_id}].FieldsList = {{{', '.join(map(str, ids))}}};\n"
                f"Background Field = {m_id};\n"
            )
    cmd = [tools["gmsh"], geo, "-3", "-o", msh, "-nt", str(threads), "-v", "2"]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=False)
    if p.returncode != 0 or not os.path.exists(msh):
        tail = (p.stdout + p.stderr).strip().splitlines()[-5:]
        raise RuntimeError("gmsh failed to tet-mesh the surface: " + " | ".join(tail))
    return read_msh2(msh)


def read_msh2(path):
    """Nodes and 10-node tets from an ASCII gmsh v2.2 file (CalculiX node order, 0-based)."""
    with open(path) as f:
        lines = f.read().split("\n")
    i = lines.index("$Nodes")
    n = int(lines[i + 1])
    arr = np.array(" ".join(lines[i + 2 : i + 2 + n]).split(), dtype=np.float64).reshape(n, 4)
    ids = arr[:, 0].astype(np.int64)
    nodes = arr[:, 1:4]
    lookup = np.full(ids.max() + 1, -1, dtype=np.int64)
    lookup[ids] = np.arange(n)
    j = lines.index("$Elements")
    ne = int(lines[j + 1])
    tets = []
    for ln in lines[j + 2 : j + 2 + ne]:
        t = ln.split()
        if t[1] == "11":
            ntag = int(t[2])
            tets.append([int(x) for x in t[3 + ntag : 3 + ntag + 10]])
    if not tets:
        raise RuntimeError("gmsh produced no quadratic tetrahedra")
    tets = lookup[np.asarray(tets, dtype=np.int64)][:, _GMSH_TO_CCX]
    used = np.unique(tets)
    remap = np.full(n, -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    return nodes[used], remap[tets]


# ----------------------------------------------------------------------------- cropping


def _ear_clip(P):
    """Triangulate a simple polygon (k,2) by ear clipping → (k-2, 3) indices (CCW order)."""
    n = len(P)
    idx = list(range(n))
    area = 0.5 * np.sum(P[:, 0] * np.roll(P[:, 1], -1) - np.roll(P[:, 0], -1) * P[:, 1])
    if area < 0:
        idx.reverse()
    tris = []

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    guard = 0
    while len(idx) > 3 and guard < 10 * n * n:
        guard += 1
        m = len(idx)
        found = False
        for k in range(m):
            i0, i1, i2 = idx[k - 1], idx[k], idx[(k + 1) % m]
            a, b, c = P[i0], P[i1], P[i2]
            if cross(a, b, c) <= 1e-14 * (np.ptp(P[:, 0]) * np.ptp(P[:, 1]) + 1e-300):
                continue
            ok = True
            for j in idx:
                if j in (i0, i1, i2):
                    continue
                q = P[j]
                if cross(a, b, q) >= 0 and cross(b, c, q) >= 0 and cross(c, a, q) >= 0:
                    ok = False
                    break
            if ok:
                tris.append((i0, i1, i2))
                idx.pop(k)
                found = True
                break
        if not found:  # numerically degenerate: clip the flattest vertex
            k = int(
                np.argmin(
                    [abs(cross(P[idx[k - 1]], P[idx[k]], P[idx[(k + 1) % m]])) for k in range(m)]
                )
            )
            idx.pop(k)
    if len(idx) == 3:
        tris.append(tuple(idx))
    return np.asarray(tris, dtype=np.int64).reshape(-1, 3)


def crop_mesh(vertices, faces, origin, normal, keep_point):
    """Keep the part of a closed mesh on the side of the plane (origin, normal) the normal points
    to, close the cut with planar caps, and return the connected piece containing
    ``keep_point`` → ``(vertices, faces)`` (closed), or raise ValueError."""
    import trimesh

    V = np.asarray(vertices, float)
    F = np.asarray(faces, np.int64)
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    s = (V - origin) @ n
    # vertices close to the plane are moved onto it, so that the cut makes no slivers
    el = np.linalg.norm(V[F[:, 0]] - V[F[:, 1]], axis=1)
    snap = np.abs(s) < 0.3 * float(np.median(el))
    V = V.copy()
    V[snap] -= np.outer(s[snap], n)
    s = np.where(snap, 0.0, s)
    keep = s >= 0
    newv = [V]
    cut_id = {}

    def cut(i, j):
        if s[i] == 0.0:  # a vertex on the plane: the cut passes through it
            return i
        if s[j] == 0.0:
            return j
        key = (i, j) if i < j else (j, i)
        if key not in cut_id:
            t = s[i] / (s[i] - s[j])
            newv.append((V[i] + t * (V[j] - V[i]))[None])
            cut_id[key] = len(V) + len(cut_id)
        return cut_id[key]

    out = [F[keep[F].all(1) & ~(s[F] == 0.0).all(1)]]  # faces lying in the plane: cap
    for f in F[keep[F].any(1) & ~keep[F].all(1)]:
        k = keep[f]
        r = int(np.argmax(k)) if k.sum() == 1 else int(np.argmin(k))
        a, b, c = f[r], f[(r + 1) % 3], f[(r + 2) % 3]
        if k.sum() == 1:  # a kept
            out.append(np.array([[a, cut(a, b), cut(a, c)]]))
        else:  # a dropped, b and c kept
            ab, ac = cut(a, b), cut(a, c)
            out.append(np.array([[ab, b, c], [ab, c, ac]]))
    Vn = np.concatenate(newv)
    Fn = np.concatenate(out)
    Fn = Fn[(Fn[:, 0] != Fn[:, 1]) & (Fn[:, 1] != Fn[:, 2]) & (Fn[:, 0] != Fn[:, 2])]
    # boundary loops on the plane → caps
    e = np.sort(np.concatenate([Fn[:, [0, 1]], Fn[:, [1, 2]], Fn[:, [2, 0]]]), axis=1)
    ue, cnt = np.unique(e, axis=0, return_counts=True)
    bnd = ue[cnt == 1]
    nbr = {}
    for a_, b_ in bnd:
        nbr.setdefault(int(a_), []).append(int(b_))
        nbr.setdefault(int(b_), []).append(int(a_))
    if any(len(v) != 2 for v in nbr.values()):
        raise ValueError("crop: the cut is not a set of simple loops (open or non-manifold mesh)")
    u = np.cross(n, [1.0, 0, 0] if abs(n[0]) < 0.9 else [0, 1.0, 0])
    u /= np.linalg.norm(u)
    w = np.cross(n, u)
    caps, seen, loops = [], set(), []
    for start in nbr:
        if start in seen:
            continue
        loop, prev, cur = [start], None, start
        seen.add(start)
        while True:
            nx = nbr[cur][0] if nbr[cur][0] != prev else nbr[cur][1]
            if nx == start:
                break
            loop.append(nx)
            seen.add(nx)
            prev, cur = cur, nx
        loops.append(np.asarray(loop))
    for loop in loops:
        P2 = np.column_stack([(Vn[loop] - origin) @ u, (Vn[loop] - origin) @ w])
        caps.append(loop[_ear_clip(P2)][:, ::-1])  # CCW in (u, w) faces +n; caps face -n
    if caps:
        Fn = np.concatenate([Fn] + caps)
    # the connected piece nearest to keep_point
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    used = np.unique(Fn)
    rows = np.repeat(np.arange(len(Fn)), 3)
    inc = coo_matrix((np.ones(rows.size), (rows, Fn.ravel())), shape=(len(Fn), len(Vn))).tocsr()
    _, lab = connected_components(inc @ inc.T, directed=False)
    vlab = np.full(len(Vn), -1)
    vlab[Fn.ravel()] = np.repeat(lab, 3)
    d = np.linalg.norm(Vn[used] - keep_point, axis=1)
    piece = vlab[used[np.argmin(d)]]
    Fk = Fn[lab == piece]
    m = trimesh.Trimesh(Vn, Fk, process=True)
    if not m.is_watertight:
        raise ValueError("crop: the cropped piece is not closed")
    return np.asarray(m.vertices), np.asarray(m.faces)


# ----------------------------------------------------------------------------- solving


def solve(
    nodes, tets, fixed, load_cases, workdir, young=3500.0, poisson=0.35, threads=2, timeout=1800
):
    """Linear static solve with CalculiX, one step per load case.

    ``fixed``: node indices held in x, y, z. ``load_cases``: list of ``(node_ids, forces (k,3))``
    in N. Returns nodal stresses ``(K, N, 6)`` in MPa, components xx, yy, zz, xy, yz, zx.
    """
    tools = _require_tools()
    fixed = np.unique(np.asarray(fixed, dtype=np.int64))
    if len(fixed) < 3:
        raise ValueError("FEM: fewer than 3 held nodes; enlarge the hold radius")
    inp = os.path.join(workdir, "job.inp")
    with open(inp, "w") as f:
        f.write("*HEADING\nosteon FEM cross-check (mm, N, MPa)\n*NODE, NSET=NALL\n")
        ids = np.arange(1, len(nodes) + 1)
        np.savetxt(f, np.column_stack([ids, nodes]), fmt="%d, %.9g, %.9g, %.9g")
        f.write("*ELEMENT, TYPE=C3D10, ELSET=EALL\n")
        np.savetxt(
            f, np.column_stack([np.arange(1, len(tets) + 1), tets + 1]), fmt="%d", delimiter=", "
        )
        f.write("*NSET, NSET=HELD\n")
        f.writelines(
            ", ".join(str(x + 1) for x in fixed[k : k + 16]) + "\n"
            for k in range(0, len(fixed), 16)
        )
        f.write(f"*BOUNDARY\nHELD, 1, 3, 0.\n*MATERIAL, NAME=MAT\n*ELASTIC\n{young}, {poisson}\n")
        f.write("*SOLID SECTION, ELSET=EALL, MATERIAL=MAT\n")
        for node_ids, forces in load_cases:
            f.write("*STEP\n*STATIC\n*CLOAD, OP=NEW\n")
            for nid, fv in zip(np.atleast_1d(node_ids), np.atleast_2d(forces), strict=True):
                for d in range(3):
                    if fv[d] != 0.0:
                        f.write(f"{nid + 1}, {d + 1}, {fv[d]:.12g}\n")
            f.write("*NODE FILE\nU\n*EL FILE\nS\n*END STEP\n")
    env = dict(
        os.environ,
        OMP_NUM_THREADS=str(threads),
        CCX_NPROC_EQUATION_SOLVER=str(threads),
        CCX_NPROC_STIFFNESS=str(threads),
        CCX_NPROC_RESULTS=str(threads),
    )
    p = subprocess.run(
        ["ccx", "-i", "job"] if tools["ccx"] is None else [tools["ccx"], "-i", "job"],
        cwd=workdir,
        capture_output=True,
        text=True,
        timeout=timeout,
        env=env,
        check=False,
    )
    frd = os.path.join(workdir, "job.frd")
    if p.returncode != 0 or not os.path.exists(frd) or "*ERROR" in p.stdout:
        tail = [ln for ln in (p.stdout + p.stderr).splitlines() if ln.strip()][-6:]
        raise RuntimeError("CalculiX failed: " + " | ".join(tail))
    S = read_frd_stress(frd, len(nodes))
    if len(S) != len(load_cases):
        raise RuntimeError(f"CalculiX wrote {len(S)} stress results for {len(load_cases)} steps")
    return S


def read_frd_stress(path, n_nodes):
    """All STRESS blocks of a CalculiX ``.frd`` file → ``(K, N, 6)`` (xx, yy, zz, xy, yz, zx)."""
    out = []
    with open(path) as f:
        lines = f.readlines()
    i = 0
    while i < len(lines):
        if lines[i].startswith(" -4  STRESS"):
            S = np.zeros((n_nodes, 6))
            i += 1
            while lines[i].startswith(" -5"):
                i += 1
            while not lines[i].startswith(" -3"):
                ln = lines[i]
                if ln.startswith(" -1"):
                    nid = int(ln[3:13])
                    vals = [float(ln[13 + 12 * k : 25 + 12 * k]) for k in range(6)]
                    if 1 <= nid <= n_nodes:
                        S[nid - 1] = vals
                i += 1
            out.append(S)
        i += 1
    return np.asarray(out)


# ----------------------------------------------------------------------------- sections


def section_cut(nodes, tets, center, normal, stresses, max_dist=None):
    """Cut the tet mesh by the plane (center, normal) and interpolate nodal stresses.

    Only the connected piece of cut tetrahedra nearest to ``center`` is kept (other body parts
    cut by the same plane are ignored). Returns ``(points (P,3), sigma_nn (K,P))``.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    n = np.asarray(normal, float)
    n = n / np.linalg.norm(n)
    c = np.asarray(center, float)
    s = (nodes - c) @ n
    st = s[tets[:, :4]]
    cut = np.nonzero((st.min(1) < 0) & (st.max(1) > 0))[0]
    if len(cut) == 0:
        return np.zeros((0, 3)), np.zeros((len(stresses), 0))
    T = tets[cut]
    # connected pieces of the cut tets (sharing a node)
    rows = np.repeat(np.arange(len(T)), 4)
    inc = coo_matrix(
        (np.ones(rows.size), (rows, T[:, :4].ravel())), shape=(len(T), len(nodes))
    ).tocsr()
    adj = inc @ inc.T
    _, lab = connected_components(adj, directed=False)
    cen = nodes[T[:, :4]].mean(1)
    inplane = (cen - c) - np.outer((cen - c) @ n, n)
    dist = np.linalg.norm(inplane, axis=1)
    keep = lab == lab[np.argmin(dist)]
    T = T[keep]
    # σ_nn at every node of the kept tets, per load case
    sn = _sigma_nn(stresses, n)  # (K, N)
    pts, vals = [], []
    for a, m, b in _TET_EDGES:
        for u, v in ((T[:, a], T[:, m]), (T[:, m], T[:, b])):
            su, sv = s[u], s[v]
            x = (su < 0) != (sv < 0)
            x &= su != sv
            if not np.any(x):
                continue
            t = su[x] / (su[x] - sv[x])
            pts.append(nodes[u[x]] + t[:, None] * (nodes[v[x]] - nodes[u[x]]))
            vals.append(sn[:, u[x]] * (1 - t) + sn[:, v[x]] * t)
    P = np.concatenate(pts)
    G = np.concatenate(vals, axis=1)
    if max_dist is not None:
        d = np.linalg.norm((P - c) - np.outer((P - c) @ n, n), axis=1)
        P, G = P[d <= max_dist], G[:, d <= max_dist]
    return P, G


def _sigma_nn(stresses, n):
    S = np.asarray(stresses)
    xx, yy, zz, xy, yz, zx = (S[..., k] for k in range(6))
    return (
        xx * n[0] ** 2
        + yy * n[1] ** 2
        + zz * n[2] ** 2
        + 2 * (xy * n[0] * n[1] + yz * n[1] * n[2] + zx * n[2] * n[0])
    )


# ----------------------------------------------------------------------------- cross-check


@dataclass
class FemSection:
    """One tested section; stresses in MPa for the force ``force`` N."""

    index: int
    bone: int
    center: np.ndarray
    normal: np.ndarray
    load_point: np.ndarray
    moment_arm_mm: float
    axial_arm_mm: float
    osteon_stress_mpa: float
    fem_stress_mpa: float
    cut_points: int
    extra: dict = field(default_factory=dict)

    @property
    def rel_error(self) -> float:
        """(osteon − FEM) / FEM."""
        return (self.osteon_stress_mpa - self.fem_stress_mpa) / self.fem_stress_mpa

    def as_dict(self):
        return {
            "section": int(self.index),
            "bone": int(self.bone),
            "center_mm": [float(x) for x in self.center],
            "normal": [float(x) for x in self.normal],
            "load_point_mm": [float(x) for x in self.load_point],
            "moment_arm_mm": float(self.moment_arm_mm),
            "axial_arm_mm": float(self.axial_arm_mm),
            "osteon_stress_mpa": float(self.osteon_stress_mpa),
            "fem_stress_mpa": float(self.fem_stress_mpa),
            "rel_error": float(self.rel_error),
            # osteon's stress with the arm measured along the section normal only: the lower
            # end of what beam theory predicts for an oblique load point (see docs/validation.md)
            "osteon_axial_arm_stress_mpa": float(
                self.osteon_stress_mpa * self.axial_arm_mm / self.moment_arm_mm
            )
            if self.moment_arm_mm > 0
            else None,
            "cut_points": int(self.cut_points),
            **self.extra,
        }


@dataclass
class FemReport:
    force_n: float
    mode: str = "crop"
    sections: list = field(default_factory=list)
    nodes: int = 0
    elements: int = 0
    mesh_size_mm: float = 0.0
    hold_point_mm: np.ndarray | None = None
    hold_radius_mm: float = 0.0
    mesh_seconds: float = 0.0
    solve_seconds: float = 0.0
    failed: list = field(default_factory=list)

    @property
    def errors(self):
        return np.array([abs(s.rel_error) for s in self.sections])

    @property
    def median_error(self):
        return float(np.median(self.errors)) if self.sections else float("nan")

    @property
    def worst_error(self):
        return float(np.max(self.errors)) if self.sections else float("nan")

    def as_dict(self):
        return {
            "force_n": self.force_n,
            "mode": self.mode,
            "nodes": self.nodes,
            "elements": self.elements,
            "mesh_size_mm": self.mesh_size_mm,
            "hold_point_mm": None
            if self.hold_point_mm is None
            else [float(x) for x in self.hold_point_mm],
            "hold_radius_mm": self.hold_radius_mm,
            "mesh_seconds": self.mesh_seconds,
            "solve_seconds": self.solve_seconds,
            "median_abs_rel_error": self.median_error,
            "worst_abs_rel_error": self.worst_error,
            "sections": [s.as_dict() for s in self.sections],
            "failed_sections": self.failed,
        }


def load_nodes(nodes, surface_nodes, point, radius):
    """Surface nodes within ``radius`` of ``point`` (at least the nearest one)."""
    d = np.linalg.norm(nodes[surface_nodes] - point, axis=1)
    sel = surface_nodes[d <= radius]
    if len(sel) == 0:
        sel = surface_nodes[[np.argmin(d)]]
    return sel


def surface_node_ids(tets):
    """Nodes on the boundary faces of a C3D10 mesh (corner and mid-side nodes)."""
    # faces by corner triples; boundary faces appear once
    fc = np.array([[0, 1, 2], [0, 1, 3], [1, 2, 3], [0, 2, 3]])
    fm = np.array([[4, 5, 6], [4, 8, 7], [5, 9, 8], [6, 9, 7]])
    F = tets[:, fc].reshape(-1, 3)
    M = tets[:, fm].reshape(-1, 3)
    key = np.sort(F, axis=1)
    _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    b = cnt[inv.ravel()] == 1
    return np.unique(np.concatenate([F[b].ravel(), M[b].ravel()]))


def find_load_point(vertices, center, normal, moment_arm):
    """The mesh vertex at distance ``moment_arm`` from ``center`` (osteon's load point: the
    downstream point farthest from the section centroid), preferring the downstream side."""
    d = np.linalg.norm(vertices - center, axis=1)
    side = (vertices - center) @ normal
    close = np.abs(d - moment_arm) <= 1e-6 * max(moment_arm, 1e-9) + 1e-9
    cand = np.nonzero(close & (side > 0))[0]
    if len(cand) == 0:
        cand = np.nonzero(close)[0]
    if len(cand) == 0:
        cand = [int(np.argmin(np.abs(d - moment_arm)))]
    return vertices[cand[0]]


def _finish_section(rep, k, s, nodes, tets, S3, force):
    c = np.asarray(s["center"], float)
    n = np.asarray(s["normal"], float)
    n = n / np.linalg.norm(n)
    _, G = section_cut(nodes, tets, c, n, S3)
    fem = float(np.max(np.linalg.norm(G, axis=0))) * force if G.shape[1] else float("nan")
    lp = np.asarray(s["load_point"], float)
    rep.sections.append(
        FemSection(
            index=int(s.get("index", k)),
            bone=int(s.get("bone", -1)),
            center=c,
            normal=n,
            load_point=lp,
            moment_arm_mm=float(s.get("moment_arm", np.linalg.norm(lp - c))),
            axial_arm_mm=float(abs((lp - c) @ n)),
            osteon_stress_mpa=float(s["osteon_stress"]),
            fem_stress_mpa=fem,
            cut_points=int(G.shape[1]),
            extra={
                k2: s[k2]
                for k2 in (
                    "tier",
                    "slenderness",
                    "end_distance",
                    "nodes",
                    "elements",
                    "surface",
                    "clamp_distance",
                )
                if k2 in s
            },
        )
    )


def _unit_cases(nodes, tets, point, radius):
    surf = surface_node_ids(tets)
    ids = load_nodes(nodes, surf, point, radius)
    cases = []
    for d in range(3):
        fv = np.zeros((len(ids), 3))
        fv[:, d] = 1.0 / len(ids)
        cases.append((ids, fv))
    return cases


@dataclass
class _Run:
    """What every FEM solve of one cross-check shares: the model (mm), its sections, the load (N),
    the material (MPa) and where and how to run."""

    V: np.ndarray
    F: np.ndarray
    sections: list
    force: float
    workdir: str
    threads: int
    young: float
    poisson: float
    progress: object
    fine_factor: float


def cross_check(
    vertices,
    faces,
    sections,
    force=20.0,
    hold_point=None,
    hold_radius=None,
    mesh_size=None,
    workdir=None,
    threads=2,
    young=3500.0,
    poisson=0.35,
    hold_plane=None,
    progress=None,
    keep_files=False,
    fine_factor=3.0,
    mode="crop",
    clamp_distance=4.0,
):
    """Run the FEM cross-check; returns a :class:`FemReport`.

    ``sections``: list of dicts with ``center``, ``normal``, ``load_point`` (mm),
    ``osteon_stress`` (MPa at ``force``) and optionally ``index``, ``bone``, ``moment_arm`` and
    ``area`` (mm², r = √(area/π)).

    ``mode="crop"`` (default): one small model per section — the mesh is cut by a plane
    ``clamp_distance`` × r upstream of the section, the cut is capped, the piece holding the
    section (everything downstream of it plus that stub) is kept, its surface is subdivided to
    edges ≤ r/``fine_factor`` (same geometry) and the capped face is clamped. The downstream part
    is a free body loaded only at the load point, so the section carries the same moment as in
    the whole model held at its root (statics), and the clamp is 2 diameters away
    (Saint-Venant); the small model keeps every run to seconds and avoids re-meshing the whole
    surface, which gmsh cannot do for every real model.

    ``mode="full"``: the whole model is re-meshed (element size ``mesh_size``, default 1/40 of
    the diagonal, refined to r/``fine_factor`` within 3 r of each section) and held at all nodes
    within ``hold_radius`` mm of ``hold_point`` (default radius: 1.25 × the depth of the point
    below the surface), or, with ``hold_plane=(point, normal)``, at all nodes on the negative
    side of that plane.
    """
    V = np.asarray(vertices, float)
    F = np.asarray(faces)
    if len(sections) == 0:
        raise ValueError("FEM cross-check: no sections to test")
    ext = float(np.linalg.norm(V.max(0) - V.min(0)))
    own_dir = workdir is None
    wd = tempfile.mkdtemp(prefix="osteon_fem_") if own_dir else workdir
    os.makedirs(wd, exist_ok=True)
    rep = FemReport(force_n=float(force), mode=mode)
    run = _Run(V, F, sections, force, wd, threads, young, poisson, progress, fine_factor)
    try:
        if mode == "crop":
            _cross_check_crop(rep, run, clamp_distance)
        elif mode == "full":
            _cross_check_full(rep, run, hold_point, hold_radius, hold_plane, mesh_size, ext)
        else:
            raise ValueError(f"FEM mode must be 'crop' or 'full', got {mode!r}")
        return rep
    finally:
        if own_dir and not keep_files:
            shutil.rmtree(wd, ignore_errors=True)


def _cross_check_crop(rep, run: _Run, clamp_distance):
    V, F, sections, wd, threads, progress = (run.V, run.F, run.sections, run.workdir, run.threads,
                                             run.progress)
    fine_factor = run.fine_factor
    for k, sec in enumerate(sections):
        c = np.asarray(sec["center"], float)
        n = np.asarray(sec["normal"], float)
        n = n / np.linalg.norm(n)
        lp = np.asarray(sec["load_point"], float)
        if (lp - c) @ n < 0:  # keep the side holding the load point
            n = -n
        area = float(sec.get("area") or 0.0)
        r = np.sqrt(area / np.pi) if area > 0 else 0.02 * float(np.ptp(V, axis=0).max())
        sub = os.path.join(wd, f"s{k}")
        os.makedirs(sub, exist_ok=True)
        t0 = time.perf_counter()
        h = r / fine_factor
        nodes = None
        errors = []
        # gmsh fails on some cut surfaces: try a few clamp distances, re-meshed surface first,
        # then the original triangles
        for cd in (clamp_distance, 1.25 * clamp_distance, 0.8 * clamp_distance):
            origin = c - cd * r * n
            try:
                Vc, Fc = crop_mesh(V, F, origin, n, c)
            except ValueError as e:
                errors.append(str(e))
                continue
            coarse = max(min(4.0 * h, 0.1 * float(np.ptp(Vc, axis=0).max())), h)
            if progress:
                progress(f"section {k + 1}/{len(sections)}: meshing")
            for remesh in (True, False):
                try:
                    nodes, tets = tet_mesh(
                        Vc,
                        Fc,
                        coarse,
                        sub,
                        threads=threads,
                        refine=[(c, 3.0 * r, h)] if remesh else (),
                        remesh=remesh,
                    )
                    sec = dict(
                        sec,
                        surface="re-meshed" if remesh else "original triangles",
                        clamp_distance=cd,
                    )
                    break
                except RuntimeError as e:
                    errors.append(str(e)[:120])
            if nodes is not None:
                break
        if nodes is None:
            rep.failed.append(
                {
                    "index": int(sec.get("index", k)),
                    "bone": int(sec.get("bone", -1)),
                    "reason": "; ".join(errors[-2:]),
                }
            )
            rep.mesh_seconds += time.perf_counter() - t0
            continue
        rep.mesh_seconds += time.perf_counter() - t0
        rep.nodes += len(nodes)
        rep.elements += len(tets)
        fixed = np.nonzero((nodes - origin) @ n <= 1e-6 * r + 1e-9)[0]
        cases = _unit_cases(nodes, tets, lp, 0.75 * h)
        if progress:
            progress(f"section {k + 1}/{len(sections)}: solving {len(nodes)} nodes")
        t1 = time.perf_counter()
        S = solve(nodes, tets, fixed, cases, sub, young=run.young, poisson=run.poisson,
                  threads=threads)
        rep.solve_seconds += time.perf_counter() - t1
        sec = dict(sec, nodes=len(nodes), elements=len(tets))
        _finish_section(rep, k, sec, nodes, tets, S, run.force)
        rep.mesh_size_mm = max(rep.mesh_size_mm, float(h))


def _cross_check_full(rep, run: _Run, hold_point, hold_radius, hold_plane, mesh_size, ext):
    V, F, sections, wd, threads, progress = (run.V, run.F, run.sections, run.workdir, run.threads,
                                             run.progress)
    fine_factor = run.fine_factor
    if mesh_size is None:
        mesh_size = ext / 40.0
    refine = []
    for sec in sections:
        if sec.get("area"):
            r_eq = float(np.sqrt(float(sec["area"]) / np.pi))
            h = float(np.clip(r_eq / fine_factor, mesh_size / 12.0, mesh_size))
            refine.append((np.asarray(sec["center"], float), 3.0 * r_eq, h))
    t0 = time.perf_counter()
    for attempt in range(4):  # coarse re-meshing of a detailed surface can fail: refine
        try:
            nodes, tets = tet_mesh(V, F, mesh_size, wd, threads=threads, refine=refine)
            break
        except RuntimeError:
            if attempt == 3:
                raise
            mesh_size *= 0.7
            refine = [(c, r, min(h, mesh_size)) for c, r, h in refine]
    rep.mesh_size_mm = float(mesh_size)
    rep.mesh_seconds = time.perf_counter() - t0
    rep.nodes, rep.elements = len(nodes), len(tets)
    if hold_plane is not None:
        hp, hn = (np.asarray(x, float) for x in hold_plane)
        fixed = np.nonzero((nodes - hp) @ hn <= 1e-6 * ext)[0]
    else:
        hold_point = np.asarray(hold_point, float)
        if hold_radius is None:
            # depth of the held point below the surface (nearest surface vertex)
            depth = float(np.min(np.linalg.norm(V - hold_point, axis=1)))
            hold_radius = max(1.25 * depth, 2.0 * mesh_size)
        fixed = np.nonzero(np.linalg.norm(nodes - hold_point, axis=1) <= hold_radius)[0]
        rep.hold_point_mm = hold_point
        rep.hold_radius_mm = float(hold_radius)
    # one set of 3 unit load cases per distinct load point
    lps = np.array([np.asarray(s["load_point"], float) for s in sections]).reshape(-1, 3)
    uniq, which = np.unique(np.round(lps, 9), axis=0, return_inverse=True)
    which = which.ravel()
    cases = []
    for p in uniq:
        cases += _unit_cases(nodes, tets, p, 0.75 * mesh_size)
    if progress:
        progress(f"solving {len(cases)} load cases on {len(nodes)} nodes")
    t1 = time.perf_counter()
    S = solve(nodes, tets, fixed, cases, wd, young=run.young, poisson=run.poisson,
              threads=threads)
    rep.solve_seconds = time.perf_counter() - t1
    for k, s in enumerate(sections):
        j = which[k]
        _finish_section(rep, k, s, nodes, tets, S[3 * j : 3 * j + 3], run.force)


def hold_point(analysis, heads):
    """The point osteon holds: the head of the held bone (mm)."""
    b = int(getattr(analysis, "held_bone", 0))
    return np.asarray(heads, float)[max(b, 0)]


def pick_sections(
    analysis, heads, tails, n=4, vertices=None, per_bone=1, tiers=((1.5, 3.0), (0.75, 2.0))
):
    """Choose up to ``n`` sections for the FEM check, at most ``per_bone`` per bone, highest
    stress first, where beam theory is meant to hold: interior sections (not at joints or bone
    ends, no flags) whose centre is outside the held region. ``tiers`` are tried in turn,
    ``(end distance, slenderness)``: a section qualifies when it is at least
    ``end distance`` × r (and half an interval) from both ends of its bone and its moment arm is
    at least ``slenderness`` × r, with r = √(area/π). Returns section dicts for
    :func:`cross_check`, each with its ``tier`` (0 = strictest), ``slenderness`` = arm / r and
    ``end_distance`` = distance to the nearer bone end / r.
    """
    a = analysis
    heads, tails = np.asarray(heads, float), np.asarray(tails, float)
    stress = np.asarray(a.stress, float)
    bone = np.asarray(a.section_bone)
    L = np.linalg.norm(tails - heads, axis=1)[bone]
    area = np.asarray(a.section_area, float)
    r = np.sqrt(np.where(area > 0, area, np.nan) / np.pi)
    t = np.asarray(getattr(a, "section_param", np.full(len(stress), np.nan)), float)
    if not np.all(np.isfinite(t)):
        u = (tails - heads)[bone]
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        t = np.einsum("ij,ij->i", np.asarray(a.section_center) - heads[bone], u)
    interval = float(getattr(a, "interval", 2.0))
    arm = np.asarray(a.moment_arm, float)
    base = np.isfinite(stress) & np.isfinite(r)
    kind = getattr(a, "section_kind", None)
    if kind is not None:
        base &= np.asarray(kind) == 0
    flags = getattr(a, "section_flags", None)
    if flags is not None:
        base &= np.asarray(flags) == 0
    hp = hold_point(a, heads)
    depth = 0.0
    if vertices is not None:
        depth = float(np.min(np.linalg.norm(np.asarray(vertices, float) - hp, axis=1)))
    centers = np.asarray(a.section_center, float)
    base &= np.linalg.norm(centers - hp, axis=1) >= 1.25 * depth + 2.0 * r
    end = np.minimum(t, L - t)
    out, count, taken = [], {}, set()
    for tier, (k_end, k_arm) in enumerate(tiers):
        ok = base & (end >= np.maximum(k_end * r, 0.5 * interval)) & (arm >= k_arm * r)
        idx = np.nonzero(ok)[0]
        idx = idx[np.argsort(-stress[idx])]
        for i in idx:
            b = int(bone[i])
            if i in taken or count.get(b, 0) >= per_bone:
                continue
            count[b] = count.get(b, 0) + 1
            taken.add(int(i))
            out.append(
                {
                    "index": int(i),
                    "bone": b,
                    "center": centers[i],
                    "normal": np.asarray(a.section_normal[i], float),
                    "load_point": np.asarray(a.load_point[i], float),
                    "moment_arm": float(arm[i]),
                    "osteon_stress": float(stress[i]),
                    "area": float(area[i]),
                    "tier": tier,
                    "slenderness": float(arm[i] / r[i]),
                    "end_distance": float(end[i] / r[i]),
                }
            )
            if len(out) >= n:
                return out
    return out
