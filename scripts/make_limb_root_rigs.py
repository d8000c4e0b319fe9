"""Build the limb-root rigs of docs/validation.md ("Limb roots: the FEM field on the plane"): a
40 x 40 x 30 mm block (the body, bottom face at z = 0) with one round limb (r = 3 mm, 36 mm long)
hanging from it, its root shaped three ways, each ONE closed mesh plus a one-bone TGF skeleton
(from inside the block, z = 20 mm, to the limb's tip):

* ``fillet``: a quarter-circle fillet of radius 5 mm (r = 8 mm at the face, 3 mm 5 mm below);
* ``cone``: a straight cone from r = 8 mm at the face to r = 3 mm 10 mm below (a sharp corner);
* ``cylinder``: no flare.

Run:  python scripts/make_limb_root_rigs.py OUT_DIR   (needs ``pip install manifold3d trimesh``)
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
    else:
        raise ValueError(f"unknown limb root {kind!r}: fillet, cone or cylinder")
    return pts + [(pts[-1][0], 1.0), (0.0, 1.0)]


def build(kind):
    """(V, F) of the block with the limb, mm, edges <= 1.5 mm."""
    import trimesh
    from manifold3d import CrossSection, Manifold

    limb = Manifold.revolve(CrossSection([profile(kind)]), SEGMENTS)
    block = Manifold.cube(BLOCK).translate((-BLOCK[0] / 2, -BLOCK[1] / 2, 0.0))
    mesh = (block + limb).to_mesh()
    v, f = trimesh.remesh.subdivide_to_size(
        np.asarray(mesh.vert_properties)[:, :3], np.asarray(mesh.tri_verts), max_edge=1.5)
    return v, f


def main(out):
    import trimesh

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    for kind in ("fillet", "cone", "cylinder"):
        v, f = build(kind)
        trimesh.Trimesh(v, f).export(out / f"{kind}.obj")
        write_tgf(out / f"{kind}.tgf", np.array([[0.0, 0.0, 20.0], [0.0, 0.0, -LIMB_LENGTH]]),
                  np.array([[0, 1]]))
        print(f"{out / kind}.obj: {len(f)} triangles")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        raise SystemExit("usage: python scripts/make_limb_root_rigs.py OUT_DIR")
    main(sys.argv[1])
