"""Tet-meshing a closed surface with the ``gmsh`` binary (quadratic 10-node tets), reading
the ``.msh`` (v2) file. Units: mm."""

from __future__ import annotations

import os
import subprocess

import numpy as np

from .tools import _require_tools

# gmsh 10-node tet: 0-3 corners, 4:(0,1) 5:(1,2) 6:(0,2) 7:(0,3) 8:(2,3) 9:(1,3)
# CalculiX C3D10:   0-3 corners, 4:(0,1) 5:(1,2) 6:(2,0) 7:(0,3) 8:(1,3) 9:(2,3)
_GMSH_TO_CCX = [0, 1, 2, 3, 4, 5, 6, 7, 9, 8]




def tet_mesh(vertices, faces, mesh_size, workdir, threads=2, timeout=600, refine=(), remesh=True):
    """Quadratic tet mesh of a closed triangle surface → ``(nodes (N,3), tets (T,10))``,
    tets in CalculiX C3D10 node order, 0-based.

    ``mesh_size`` mm is the element size away from the refined regions; ``refine`` is a list of
    ``(center (3,), radius mm, size mm)`` balls meshed finer (the tested sections).
    ``remesh=False`` keeps the given surface triangles (only the interior is meshed; sizes grow
    from the surface up to ``mesh_size``). gmsh is stopped after ``timeout`` s; that, like any
    gmsh failure, raises ``RuntimeError``.
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
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=False)
    except subprocess.TimeoutExpired:
        # gmsh can loop for ever on some surfaces (seen on a capped crop of a shoulder): a
        # failure the callers try the next set-up on, not a crash
        raise RuntimeError(f"gmsh did not finish tet-meshing the surface within {timeout:g} s "
                           "(stopped)") from None
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
