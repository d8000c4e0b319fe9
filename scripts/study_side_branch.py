"""A one-sided corner (issue 33, docs/notch.md "Limits"): a round branch entering a round body
from the side, osteon's corner reading at several rotations about the branch's axis against FEM.

The shape (mm): a body, a cylinder of diameter D = 12 along x from x = -30 to 30; a branch, a
cylinder of diameter d = 6 along z from the body's axis to z = 36 (30 mm out of the body), the
junction edge filleted with r = rel_r d (gmsh's OpenCASCADE kernel, like
tests/python/stepped_bars.py, whose size field and element order this reuses).
Load: 1 N at the branch's tip, along +x, -x (the plane of the body's axis: the corner there
meets the body's flat generatrix) and, as a third load case of the same solve, along y (the
plane across the body: the corner meets its curved side). The body is held at its x = -30 end
only (osteon's root: the body bone's head); the branch's moment at its root does not depend on
how the body is held, but the body's own bending stress adds a few % on the clamp's side
(+x 3.05 / -x 2.87 MPa at r/4 on the T; held at both ends 2.93 / 2.94).
FEM: CalculiX, quadratic tets, element size r/4 and r/6 on the fillet; peak = the largest
maximum principal stress of the nodes near the fillet (as stepped_bars.fem_peak).
osteon: the same OCC shape meshed in 2D (r/2 on the fillet, d/8 elsewhere, as
stepped_bars.osteon_peak), a body bone (-30,0,0)->(30,0,0) held at its head and a branch bone
(0,0,z0)->(0,0,36) (z0 in HEAD_ZS shifts the 2 mm sections), automatic weights, force 1 N,
notch_sensitivity 1, min_notch_radius 0.01 mm; run on the mesh and skeleton turned about z (the
branch's axis) by each angle, on each turn's mirror (x -> -x, faces flipped) and on the shape
re-meshed turned. Read: the branch bone's sections from 1.2 mm below the junction to 6 mm above
it; the corner reading is the one with the largest governing stress.

    nice .venv/bin/python scripts/study_side_branch.py [--rel-r 0.1] [--tilt 45]

``--tilt T`` turns the body about y by T degrees (the branch stays along z): a tail root, the
corner acute (90 - T) on the -x side, obtuse on the other; the body bone follows the tilt.
FEM then has three load cases at the tip (+x, -x, +y); the reference is the worst.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "python"))
from stepped_bars import FORCE, size_field

BODY_D = 12.0  # D, mm
BRANCH_D = 6.0  # d, mm
HALF_LENGTH = 30.0  # the body spans x = -30 .. 30, mm
TIP_Z = BODY_D / 2 + 30.0  # the branch's tip, mm
ANGLES = (0.0, 11.25, 22.5, 33.75)  # degrees about z: one period of the 8 half-planes (45 deg)
#: the branch bone's head on the body's axis: sections every 2 mm from it, so these put the
#: plane nearest the junction at z = 6 (tangent to the body's top), 6.5 (in the fillet), 7, 7.5
HEAD_ZS = (0.0, 0.5, 1.0, 1.5)
#: None: the round branch (d = BRANCH_D); (a, b): an elliptic branch, semi-axes a along x (the
#: tilt plane) and b along y, mm (scripts/study_junction.py's round "6-ellipse"; set_branch)
BRANCH_SEMI = None


def set_branch(semi=None):
    """Use an elliptic branch of semi-axes (a along x, b along y) mm, or the round one (None)."""
    global BRANCH_SEMI
    BRANCH_SEMI = None if semi is None else (float(semi[0]), float(semi[1]))


def branch_semi():
    return BRANCH_SEMI or (BRANCH_D / 2, BRANCH_D / 2)


def branch_radius_at(x, y):
    """The branch's outline's distance from its axis in the direction (x, y)."""
    a, b = branch_semi()
    phi = np.arctan2(y, x)
    return a * b / np.sqrt((b * np.cos(phi)) ** 2 + (a * np.sin(phi)) ** 2)


def body_axis(tilt_deg):
    """The body's axis (unit): x turned by tilt_deg about y (the branch stays along z; a tilt
    makes the corner acute on one side, obtuse on the other, like a tail root)."""
    t = math.radians(tilt_deg)
    return np.array([math.cos(t), 0.0, -math.sin(t)])


def junction_z(tilt_deg):
    """(lowest, highest) z where the branch's side meets the body's, mm."""
    u = body_axis(tilt_deg)
    zs = []
    sa, sb = branch_semi()
    for phi in np.linspace(0, 2 * math.pi, 721):
        cx = sa * math.cos(phi) * u[0]
        # |p|^2 - (p.u)^2 = (D/2)^2 with p = (a cos, b sin, z): a quadratic in z
        rr = (sa * math.cos(phi)) ** 2 + (sb * math.sin(phi)) ** 2 if BRANCH_SEMI else (BRANCH_D / 2) ** 2
        a, b, c = 1 - u[2] ** 2, -2 * cx * u[2], rr - cx**2 - (BODY_D / 2) ** 2
        zs.append((-b + math.sqrt(b * b - 4 * a * c)) / (2 * a))
    return min(zs), max(zs)


def build(gmsh, radius, tilt_deg=0.0):
    """The filleted T (the body tilted by tilt_deg about y) in gmsh's OCC kernel; returns
    (volume tag, fillet surface tags). Written beside stepped_bars.build, not through it: the
    pre-registered bar study records that file's SHA-1 with its FEM cache (study_notch.py)."""
    occ = gmsh.model.occ
    body = occ.addCylinder(-HALF_LENGTH, 0, 0, 2 * HALF_LENGTH, 0, 0, BODY_D / 2)
    if tilt_deg:
        occ.rotate([(3, body)], 0, 0, 0, 0, 1, 0, math.radians(tilt_deg))
    if BRANCH_SEMI is None:
        branch = occ.addCylinder(0, 0, 0, 0, 0, TIP_Z, BRANCH_D / 2)
    else:  # OCC's ellipse wants its major axis along x: turned a quarter about z if a < b
        a, b = BRANCH_SEMI
        disk = occ.addDisk(0, 0, 0, max(a, b), min(a, b))
        if a < b:
            occ.rotate([(2, disk)], 0, 0, 0, 0, 0, 1, math.pi / 2)
        branch = next(t for d, t in occ.extrude([(2, disk)], 0, 0, TIP_Z) if d == 3)
    fused, _ = occ.fuse([(3, body)], [(3, branch)])
    occ.synchronize()
    vol = fused[0][1]
    # the junction's edges lie on the branch's side (within d/2 of z), below its tip
    edges = []
    for _, e in gmsh.model.getEntities(1):
        b = gmsh.model.getBoundingBox(1, e)
        if b[2] > 1.0 and b[5] < TIP_Z - 1 and max(map(abs, (b[0], b[1], b[3], b[4]))) < max(
                branch_semi()) + 0.2:
            edges.append(e)
    if not edges:
        raise RuntimeError("the junction's edge was not found")
    out = occ.fillet([vol], edges, [radius], removeVolume=True)
    occ.synchronize()
    vol = out[0][1]
    # the fillet: neither the branch's side nor its tip (up to z = TIP_Z) nor the body's side and
    # ends (reaching |x| ~ 30 cos(tilt))
    fillet = []
    for _, s in gmsh.model.getBoundary([(3, vol)], oriented=False):
        b = gmsh.model.getBoundingBox(2, s)
        if b[5] < TIP_Z - 1 and max(abs(b[0]), abs(b[3])) < 15:
            fillet.append(s)
    if not fillet:
        raise RuntimeError("no fillet surface found")
    return vol, fillet


def mesh_shape(rel_r, dim, fine_div, turn_deg=0.0, tilt_deg=0.0):
    """dim 2 -> (vertices, triangles); dim 3 -> (nodes, C3D10 tets), as stepped_bars.mesh_shape.
    ``turn_deg``: the OCC shape turned about z before meshing and the mesh turned back (the same
    shape in the same place, meshed differently: the mesh's own points set the planes' phase)."""
    import gmsh

    radius = rel_r * BRANCH_D
    gmsh.initialize(["-nt", "1"])
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        gmsh.model.add("side_branch")
        vol, fillet = build(gmsh, radius, tilt_deg)
        if turn_deg:
            gmsh.model.occ.rotate([(3, vol)], 0, 0, 0, 0, 0, 1, math.radians(turn_deg))
            gmsh.model.occ.synchronize()
        if dim == 2:
            size_field(gmsh, fillet, radius / fine_div, BRANCH_D / 8, BRANCH_D / 8)
        else:
            size_field(gmsh, fillet, radius / fine_div, BRANCH_D / 6, BRANCH_D / 2)
        gmsh.model.mesh.generate(dim)
        if dim == 3:
            gmsh.model.mesh.setOrder(2)
        tags, coords, _ = gmsh.model.mesh.getNodes()
        index = {int(t): k for k, t in enumerate(tags)}
        xyz = coords.reshape(-1, 3) @ turn_about_z(-turn_deg).T
        etype, per = (2, 3) if dim == 2 else (11, 10)
        _, enodes = gmsh.model.mesh.getElementsByType(etype)
        elems = np.array([index[int(t)] for t in enodes], dtype=np.int64).reshape(-1, per)
    finally:
        gmsh.finalize()
    if dim == 2:
        used = np.unique(elems)
        remap = -np.ones(len(xyz), dtype=np.int64)
        remap[used] = np.arange(len(used))
        return xyz[used], remap[elems].astype(np.int32)
    return xyz, elems[:, [0, 1, 2, 3, 4, 5, 6, 7, 9, 8]]  # gmsh -> CalculiX C3D10


def turn_about_z(deg):
    a = math.radians(deg)
    return np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])


def max_principal(s):
    """The largest principal stress per node (osteon.fem.peaks: the one reading code)."""
    from osteon.fem.peaks import max_principal as reading

    return reading(s)


#: FEM load cases at the branch's tip, unit directions: +x, -x (the tilted body's acute and
#: obtuse sides in tension in turn), +y
LOADS = ((1.0, 0.0, 0.0), (-1.0, 0.0, 0.0), (0.0, 1.0, 0.0))


def fem_solution(rel_r, fine_div, tilt_deg=0.0):
    """FEM of the T, the LOADS at the branch's tip: (nodes, stresses (3,N,6), seconds)."""
    from osteon.fem.solve import solve

    t0 = time.time()
    nodes, tets = mesh_shape(rel_r, 3, fine_div, tilt_deg=tilt_deg)
    # the body's end cap: its nodes past -HALF_LENGTH along the body's axis *and* within the
    # body's radius of it (past 45 degrees of tilt the branch's tip also lies past that plane)
    u = body_axis(tilt_deg)
    along = nodes @ u
    off_axis = np.linalg.norm(nodes - np.outer(along, u), axis=1)
    held = np.flatnonzero((along < -HALF_LENGTH + 1e-4) & (off_axis < BODY_D / 2 + 1e-3))
    tip = np.flatnonzero(nodes[:, 2] > TIP_Z - 1e-6)
    cases = [(tip, np.tile(np.array(load) * FORCE / len(tip), (len(tip), 1))) for load in LOADS]
    with tempfile.TemporaryDirectory() as work:
        stresses = solve(nodes, tets, held, cases, work, threads=2)
    return nodes, stresses, time.time() - t0


def fem_peak(nodes, stresses, rel_r, tilt_deg=0.0, z_lo=None, z_hi=None):
    """Largest max principal stress (MPa) per load case of the nodes by the fillet (the branch's
    surface band from below the junction to above the fillet), or of the band z_lo .. z_hi."""
    # a fillet of radius r in a corner of angle a meets its faces r / tan(a / 2) from the edge:
    # r on the T (90 deg), 2.4 r in the tilted body's acute corner (90 - tilt)
    reach = 1.1 * rel_r * BRANCH_D / math.tan(math.radians(90 - abs(tilt_deg)) / 2)
    rad = np.hypot(nodes[:, 0], nodes[:, 1])
    if BRANCH_SEMI is not None:  # the distance from the elliptic outline, plus d/2 (as a round's)
        rad = rad - branch_radius_at(nodes[:, 0], nodes[:, 1]) + BRANCH_D / 2
    if z_lo is None:
        low, high = junction_z(tilt_deg)
        z_lo, z_hi = low - 2 * rel_r * BRANCH_D, high + reach
    zone = ((nodes[:, 2] > z_lo) & (nodes[:, 2] < z_hi)
            & (rad < BRANCH_D / 2 + reach) & (rad > BRANCH_D / 2 - 0.05 * BRANCH_D))
    if not zone.any():
        return [float("nan")] * len(stresses)
    return [float(max_principal(s[zone]).max()) for s in stresses]


def osteon_sections(vertices, faces, head_z, turn_deg=0.0, mirror=False, tilt_deg=0.0):
    """The branch bone's sections from 1.2 mm below the junction to 6 mm (two thin radii) above
    it (4 < z < 12 on the T), as dicts, on the model turned by turn_deg about z (mesh and
    skeleton) and mirrored (x -> -x) if asked. ``head_z``: the branch bone's head (on the body's
    axis, moved up to shift the 2 mm sections along the branch)."""
    from osteon import Skeleton, analyze

    rot = turn_about_z(turn_deg)
    if mirror:
        rot = np.diag([-1.0, 1.0, 1.0]) @ rot
        faces = faces[:, [0, 2, 1]]  # keep the normals outward
    u = body_axis(tilt_deg)
    heads = np.array([-HALF_LENGTH * u, [0, 0, head_z]]) @ rot.T
    tails = np.array([HALF_LENGTH * u, [0, 0, TIP_Z]]) @ rot.T
    sk = Skeleton(heads, tails, [-1, 0])
    res = analyze(np.ascontiguousarray(vertices @ rot.T), np.ascontiguousarray(faces), sk,
                  force=FORCE, allowable_stress=1e9, root=0, min_notch_radius=0.01,
                  notch_sensitivity=1.0)
    z = np.asarray(res.section_point)[:, 2]
    low, high = junction_z(tilt_deg)
    near = (np.asarray(res.section_bone) == 1) & (z > low - 1.2) & (z < high + 6.0)
    return [{"z": float(z[k]), "stress": float(res.stress[k]),
             "nominal": float(res.nominal_stress[k]), "kt": float(res.stress_concentration[k]),
             "radius": float(res.notch_radius[k]), "modulus": float(res.section_modulus[k])}
            for k in np.flatnonzero(near)]


def cell(sec):
    return (f"{sec['kt']:.2f} / {sec['radius']:.2f} / {sec['stress']:.2f} / {sec['nominal']:.2f} "
            f"(z {sec['z']:.1f})")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rel-r", type=float, default=0.1, help="fillet radius / d")
    ap.add_argument("--tilt", type=float, default=0.0,
                    help="degrees the body is turned about y (0: the T; 45: a tail root)")
    args = ap.parse_args()
    rel_r, tilt = args.rel_r, args.tilt
    radius = rel_r * BRANCH_D
    modulus = math.pi * BRANCH_D**3 / 32
    low, high = junction_z(tilt)
    print(f"## Side branch D = {BODY_D:g}, d = {BRANCH_D:g}, r = {radius:g} mm (r/d = {rel_r:g}), "
          f"body tilted {tilt:g}°: junction at z = {low:.2f} .. {high:.2f}\n")
    if not tilt:
        root_z = BODY_D / 2 + radius  # the fillet meets the branch here in the x-z plane
        print(f"Closed form at the fillet's root (z = {root_z:.2f}): M/W = F (L - z) / (pi d^3/32)"
              f" = {FORCE * (TIP_Z - root_z) / modulus:.3f} MPa\n")
    print("| FEM fillet size | nodes | " + " | ".join(f"peak, load {d} (MPa)" for d in LOADS)
          + " | s |")
    print("|---|---|" + "---|" * len(LOADS) + "---|")
    for div in (4, 6):
        nodes, stresses, sec = fem_solution(rel_r, div, tilt)
        peaks = fem_peak(nodes, stresses, rel_r, tilt)
        print(f"| r/{div} = {radius / div:.3f} mm | {len(nodes)} | "
              + " | ".join(f"{p:.3f}" for p in peaks) + f" | {sec:.0f} |", flush=True)
    worst_case = int(np.argmax(peaks))
    peak = peaks[worst_case]  # osteon loads the worst point in the worst direction
    vertices, faces = mesh_shape(rel_r, 2, 2, tilt_deg=tilt)
    print(f"\nosteon mesh: {len(faces)} triangles; FEM reference: the r/{div} peak {peak:.3f} MPa "
          f"(load {LOADS[worst_case]})\n")

    print("Every branch section, model unturned (osteon: Kt, radius mm, governing, nominal MPa, W "
          "mm^3; FEM r/6: peak within 0.25 mm of the plane, the same load; ratio governing / that)"
          "\n")
    print("| head z | plane z | Kt | r (mm) | governing | nominal | W | FEM at plane | ratio |")
    print("|---|---|---|---|---|---|---|---|---|")
    for head_z in HEAD_ZS:
        for s in osteon_sections(vertices, faces, head_z, tilt_deg=tilt):
            local = fem_peak(nodes, stresses, rel_r, tilt, s["z"] - 0.25, s["z"] + 0.25)
            local = local[worst_case]
            print(f"| {head_z:g} | {s['z']:.2f} | {s['kt']:.2f} | {s['radius']:.2f} "
                  f"| {s['stress']:.3f} | {s['nominal']:.3f} | {s['modulus']:.1f} | {local:.3f} "
                  f"| {s['stress'] / local:.2f} |", flush=True)

    print("\nThe corner reading (the branch section of largest governing stress) per variant: "
          "Kt / r (mm) / governing / nominal (MPa) (plane z); last: governing / FEM peak\n")
    print("| variant | " + " | ".join(f"head z {h:g}" for h in HEAD_ZS) + " |")
    print("|---|" + "---|" * len(HEAD_ZS))
    remeshed = {a: mesh_shape(rel_r, 2, 2, a, tilt) for a in ANGLES[1:]}
    variants = [(f"turned {a:g}°", vertices, faces, a, False) for a in ANGLES]
    variants += [(f"mirror, turned {a:g}°", vertices, faces, a, True) for a in ANGLES]
    variants += [(f"remeshed at {a:g}°", *remeshed[a], 0.0, False) for a in ANGLES[1:]]
    for label, v, f, turn, mirror in variants:
        row = []
        for head_z in HEAD_ZS:
            secs = osteon_sections(v, f, head_z, turn, mirror, tilt)
            worst = max(secs, key=lambda s: s["stress"])
            row.append(f"{cell(worst)} {worst['stress'] / peak:.2f}")
        print(f"| {label} | " + " | ".join(row) + " |", flush=True)


if __name__ == "__main__":
    main()
