"""Stepped round bars with a shoulder fillet (issue 33): built with gmsh's OpenCASCADE kernel
(the ``gmsh`` Python wheel), FEM peak at the fillet with CalculiX, and osteon's governing stress
there. Test tooling (gmsh is no dependency of the wheel): used by tests/python/test_notch.py
and scripts/study_notch.py (the pre-registered study; its docstring says how). Units: mm, N, MPa; d = ``D_SMALL``, D = step x d, r = rel_r x d."""

from __future__ import annotations

import numpy as np

D_SMALL = 6.0  # d, mm
FORCE = 1.0  # N
#: quadratic tets with straight edges (midside nodes not moved onto the curved surface): the
#: retry when CalculiX stops on a nonpositive jacobian (scripts/study_notch.py does it itself)
STRAIGHT_MIDSIDE = False


def build(gmsh, big, small, radius):
    """The filleted stepped bar in gmsh's OCC kernel; returns the fillet's surface tags."""
    occ = gmsh.model.occ
    thick = occ.addCylinder(0, 0, -1.5 * big, 0, 0, 1.5 * big, big / 2)
    thin = occ.addCylinder(0, 0, 0, 0, 0, 5 * small, small / 2)
    fused, _ = occ.fuse([(3, thick)], [(3, thin)])
    occ.synchronize()
    vol = fused[0][1]
    # The shoulder's inner circular edge: the circle of radius d/2 at z = 0.
    target = []
    for _, e in gmsh.model.getEntities(1):
        box = gmsh.model.getBoundingBox(1, e)
        if abs(box[2]) < 1e-3 and abs(box[5]) < 1e-3 and abs(box[3] - small / 2) < 1e-2:
            target.append(e)
    out = occ.fillet([vol], target, [radius], removeVolume=True)
    occ.synchronize()
    vol = out[0][1]
    if not target:
        raise RuntimeError("the shoulder's edge was not found")
    fillet = []
    for _, s in gmsh.model.getBoundary([(3, vol)], oriented=False):
        # the fillet: starts at z = 0 and rises (the shoulder face is flat at z = 0, the thin
        # bar's side starts at z = r); OCC's boxes of curved patches are loose, so no upper
        # check on z, and none on the radius (a fillet close to the step's height, r/d 0.09 at
        # D/d 1.2, has a box wider than D)
        b = gmsh.model.getBoundingBox(2, s)
        if abs(b[2]) < 1e-3 and b[5] > 1e-3 and b[5] < 5 * small - 1e-3:
            fillet.append(s)
    if len(fillet) != 1:
        raise RuntimeError(f"expected one fillet surface, found {fillet}")
    return vol, fillet


def size_field(gmsh, fillet, fine, near, far):
    f = gmsh.model.mesh.field
    dist = f.add("Distance")
    f.setNumbers(dist, "SurfacesList", fillet)
    thr = f.add("Threshold")
    f.setNumber(thr, "InField", dist)
    f.setNumber(thr, "SizeMin", fine)
    f.setNumber(thr, "SizeMax", far)
    f.setNumber(thr, "DistMin", fine)
    f.setNumber(thr, "DistMax", 3 * near)
    f.setAsBackgroundMesh(thr)
    for k in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints", "MeshSizeFromCurvature"):
        gmsh.option.setNumber("Mesh." + k, 0)


def mesh_shape(step, rel_r, dim, fine_div):
    """Nodes and elements of the bar: dim 2 -> (vertices, triangles), dim 3 -> (nodes, tets10)."""
    import gmsh

    big, small = step * D_SMALL, D_SMALL
    radius = rel_r * D_SMALL
    gmsh.initialize(["-nt", "1"])
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        gmsh.model.add("bar")
        _, fillet = build(gmsh, big, small, radius)
        if dim == 2:
            size_field(gmsh, fillet, radius / fine_div, small / 8, small / 8)
        else:
            size_field(gmsh, fillet, radius / fine_div, small / 6, small / 2)
        gmsh.model.mesh.generate(dim)
        if dim == 3:
            if STRAIGHT_MIDSIDE:  # retry of a CalculiX "nonpositive jacobian": straight edges
                gmsh.option.setNumber("Mesh.SecondOrderLinear", 1)
            gmsh.model.mesh.setOrder(2)
        tags, coords, _ = gmsh.model.mesh.getNodes()
        index = {int(t): k for k, t in enumerate(tags)}
        xyz = coords.reshape(-1, 3)
        etype = 2 if dim == 2 else 11
        _, enodes = gmsh.model.mesh.getElementsByType(etype)
        per = 3 if dim == 2 else 10
        elems = np.array([index[int(t)] for t in enodes], dtype=np.int64).reshape(-1, per)
    finally:
        gmsh.finalize()
    if dim == 2:  # keep only the vertices the triangles use
        used = np.unique(elems)
        remap = -np.ones(len(xyz), dtype=np.int64)
        remap[used] = np.arange(len(used))
        return xyz[used], remap[elems].astype(np.int32)
    # gmsh's 10-node tet order -> CalculiX C3D10 (edges 9 and 10 swapped)
    elems = elems[:, [0, 1, 2, 3, 4, 5, 6, 7, 9, 8]]
    return xyz, elems


def fem_peak(step, rel_r, fine_div, workdir):
    from osteon.fem.peaks import max_principal
    from osteon.fem.solve import solve

    big, small = step * D_SMALL, D_SMALL
    radius = rel_r * D_SMALL
    nodes, tets = mesh_shape(step, rel_r, 3, fine_div)
    held = np.flatnonzero(nodes[:, 2] < -1.5 * big + 1e-6)
    tip = np.flatnonzero(nodes[:, 2] > 5 * small - 1e-6)
    forces = np.zeros((len(tip), 3))
    forces[:, 0] = FORCE / len(tip)
    S = solve(nodes, tets, held, [(tip, forces)], workdir, threads=1)[0]
    rad = np.hypot(nodes[:, 0], nodes[:, 1])
    zone = ((nodes[:, 2] > -0.1 * radius) & (nodes[:, 2] < 1.1 * radius)
            & (rad < small / 2 + 1.1 * radius) & (rad > small / 2 - 0.05 * small))
    principal = max_principal(S[zone])  # osteon.fem.peaks: the one reading code
    return float(principal.max()), len(nodes)


def osteon_peak(step, rel_r):
    from osteon import Skeleton, analyze

    big, small = step * D_SMALL, D_SMALL
    vertices, faces = mesh_shape(step, rel_r, 2, 2)
    heads = np.array([[0.0, 0.0, -1.5 * big]])
    tails = np.array([[0.0, 0.0, 5 * small]])
    sk = Skeleton(heads, tails, [-1])
    a = analyze(vertices, faces, sk, force=FORCE, allowable_stress=1e9, root=0,
                       min_notch_radius=0.01, notch_sensitivity=1.0)
    notch = a.notch
    if not notch.any():
        return 0.0, float("nan"), float("nan"), len(faces)
    k = int(np.argmax(np.where(notch, a.stress, -np.inf)))
    return float(a.stress[k]), float(a.notch_radius[k]), float(a.stress_concentration[k]), len(faces)
