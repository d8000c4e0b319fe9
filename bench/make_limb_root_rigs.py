"""Build the limb-root rigs of docs/validation.md ("Limb roots: the FEM field on the plane"): a
40 x 40 x 30 mm block (the body, bottom face at z = 0) with one round limb (r = 3 mm, 36 mm long)
hanging from it, its root shaped three ways, each ONE closed mesh plus a one-bone TGF skeleton
(from inside the block, z = 20 mm, to the limb's tip):

* ``fillet``: a quarter-circle fillet of radius 5 mm (r = 8 mm at the face, 3 mm 5 mm below);
* ``cone``: a straight cone from r = 8 mm at the face to r = 3 mm 10 mm below (a sharp corner);
* ``cylinder``: no flare.

and four held-out rigs (docs/validation.md "Limb roots: a held-out test of the gate"), limb
r = 3 mm, 66 mm tall (``--height-mm 66`` keeps the size) but for ``fused`` (80 mm:
``--height-mm 80``):

* ``fused``: the limb lying fused along a side face of the block (axis 2 mm outside the face
  x = 20, so 1 mm of it is merged with the block) for its top 10 mm (z 10 -> 0), then free and
  straight for 50 mm (z 0 -> -50), like a forearm along a torso; the bone along the limb. (50,
  not 36 mm: a plane along the fused part also cuts the block, whose slice below the plane is
  downstream of it; with 36 mm the block's far bottom corner, not the limb's tip, is the
  farthest point downstream and so osteon's load point, and `validate --junctions` finds no
  section to test);
* ``plate``: the limb (64 mm) hanging perpendicular from a thin plate 40 x 40 x 2 mm (thinner
  than r), the bone from the middle of the plate (z = 1 mm) to the tip;
* ``necked``: the cylinder, with a neck 2 mm below the face: r = 2 mm for |z + 2| <= 0.75 mm,
  cosine ramps back to r = 3 mm over 1 mm on either side (z -3.75 ... -0.25 mm);
* ``oblique``: the cylinder entering the block's bottom face at 45 degrees (its axis through
  the face's centre, 20 mm of it inside the block), the bone along the axis.

Run:  python bench/make_limb_root_rigs.py OUT_DIR [KIND ...]   (default: all seven; needs
``pip install manifold3d trimesh``)
Then: osteon validate OUT_DIR/fillet.obj --skeleton OUT_DIR/fillet.tgf --height-mm 66 \\
          --fem --junctions --sections 4
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from osteon.io import write_tgf

SEGMENTS = 64
LIMB_RADIUS, LIMB_LENGTH, FLARE, CONE_LENGTH = 3.0, 36.0, 5.0, 10.0  # mm
BLOCK = (40.0, 40.0, 30.0)  # mm
KINDS = ("fillet", "cone", "cylinder", "fused", "plate", "necked", "oblique")
# mm: the fused limb's axis outside the face, its fused and free lengths
FUSED_OFFSET, FUSED_LENGTH, FUSED_FREE = 2.0, 10.0, 50.0
PLATE, PLATE_LIMB = (40.0, 40.0, 2.0), 64.0  # mm
NECK_RADIUS, NECK_DEPTH, NECK_FLAT, NECK_RAMP = 2.0, 2.0, 1.5, 1.0  # mm
OBLIQUE_INSIDE = 20.0  # mm of the oblique limb's axis inside the block
# the oblique limb's length outside the block: its lowest point at z = -LIMB_LENGTH
OBLIQUE_OUTSIDE = (LIMB_LENGTH - LIMB_RADIUS * np.sin(np.pi / 4)) / np.cos(np.pi / 4)


def profile(kind):
    """(r, z) outline of the limb (mm), from its tip up to 1 mm inside the block."""
    pts = [(0.0, -LIMB_LENGTH), (LIMB_RADIUS, -LIMB_LENGTH)]
    if kind == "fillet":  # r(t) = r0 + rho - sqrt(rho^2 - (rho - t)^2), t = -z in [0, rho]
        for t in np.linspace(FLARE, 0.0, 25):
            pts.append((LIMB_RADIUS + FLARE - np.sqrt(max(FLARE**2 - (FLARE - t) ** 2, 0.0)), -t))
    elif kind == "cone":
        pts += [(LIMB_RADIUS, -CONE_LENGTH), (LIMB_RADIUS + FLARE, 0.0)]
    elif kind == "cylinder":
        pts.append((LIMB_RADIUS, 0.0))
    elif kind == "necked":  # r = 2 mm over 1.5 mm, 2 mm below the face, cosine ramps of 1 mm
        half = NECK_FLAT / 2
        for z in np.linspace(-NECK_DEPTH - half - NECK_RAMP, 0.0, 57):
            d = max(abs(z + NECK_DEPTH) - half, 0.0)  # distance from the neck's flat part
            w = 0.5 * (1 + np.cos(np.pi * d / NECK_RAMP)) if d < NECK_RAMP else 0.0
            pts.append((LIMB_RADIUS - (LIMB_RADIUS - NECK_RADIUS) * w, z))
    else:
        raise ValueError(f"unknown limb root {kind!r}: fillet, cone, cylinder or necked")
    return pts + [(pts[-1][0], 1.0), (0.0, 1.0)]


def build(kind):
    """(V, F) of the block with the limb, mm, edges <= 1.5 mm."""
    import trimesh
    from manifold3d import CrossSection, Manifold

    if kind == "fused":
        limb = Manifold.cylinder(FUSED_FREE + FUSED_LENGTH, LIMB_RADIUS, LIMB_RADIUS, SEGMENTS)
        limb = limb.translate((BLOCK[0] / 2 + FUSED_OFFSET, 0.0, -FUSED_FREE))
    elif kind == "plate":
        limb = Manifold.cylinder(PLATE_LIMB + PLATE[2] / 2, LIMB_RADIUS, LIMB_RADIUS, SEGMENTS)
        limb = limb.translate((0.0, 0.0, -PLATE_LIMB))
    elif kind == "oblique":  # along +z from -OUTSIDE to +INSIDE, tilted 45 degrees about y
        limb = Manifold.cylinder(OBLIQUE_OUTSIDE + OBLIQUE_INSIDE, LIMB_RADIUS, LIMB_RADIUS,
                                 SEGMENTS).translate((0.0, 0.0, -OBLIQUE_OUTSIDE))
        limb = limb.rotate((0.0, -45.0, 0.0))
    else:
        limb = Manifold.revolve(CrossSection([profile(kind)]), SEGMENTS)
    body = PLATE if kind == "plate" else BLOCK
    block = Manifold.cube(body).translate((-body[0] / 2, -body[1] / 2, 0.0))
    mesh = (block + limb).to_mesh()
    v, f = trimesh.remesh.subdivide_to_size(
        np.asarray(mesh.vert_properties)[:, :3], np.asarray(mesh.tri_verts), max_edge=1.5)
    return v, f


def bone(kind):
    """(head, tail) of the rig's one bone, mm."""
    if kind == "fused":
        x = BLOCK[0] / 2 + FUSED_OFFSET
        return (x, 0.0, FUSED_LENGTH), (x, 0.0, -FUSED_FREE)
    if kind == "plate":
        return (0.0, 0.0, PLATE[2] / 2), (0.0, 0.0, -PLATE_LIMB)
    if kind == "oblique":
        d = np.array([np.sin(np.pi / 4), 0.0, -np.cos(np.pi / 4)])  # down and out
        return tuple(-OBLIQUE_INSIDE * d), tuple(OBLIQUE_OUTSIDE * d)
    return (0.0, 0.0, 20.0), (0.0, 0.0, -LIMB_LENGTH)


def main(out, kinds=KINDS):
    import trimesh

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    for kind in kinds:
        v, f = build(kind)
        trimesh.Trimesh(v, f).export(out / f"{kind}.obj")
        write_tgf(out / f"{kind}.tgf", np.array(bone(kind)), np.array([[0, 1]]))
        print(f"{out / kind}.obj: {len(f)} triangles")


if __name__ == "__main__":
    if len(sys.argv) < 2 or any(k not in KINDS for k in sys.argv[2:]):
        raise SystemExit("usage: python bench/make_limb_root_rigs.py OUT_DIR [KIND ...], "
                         f"KIND one of {', '.join(KINDS)}")
    main(sys.argv[1], sys.argv[2:] or KINDS)
