"""Build the junction test rig of docs/validation.md: a thin spine with side branches, as ONE
closed mesh (a boolean union of cylinders and a sphere, manifold3d), plus a TGF skeleton.

Side branches the spine's sections cut through: shoulders (two arms along ±y at x = 44 mm),
hips (two legs along ±y at x = 12 mm), a dorsal fin stub (+z at x = 28 mm, no bone) and the
tail base (a tail leaving the spine's start downwards at 45°). Units mm; the spine is r = 3.5,
the limbs r = 3, the fin r = 3.5 and 7 mm tall.

Run:  python bench/make_junction_rig.py OUT_DIR   (needs ``pip install manifold3d``)
Then: osteon validate OUT_DIR/junction_rig.obj --skeleton OUT_DIR/junction_rig.tgf \
          --height-mm 0 --fem --junctions --sections 4
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from osteon.io import write_tgf

SEGMENTS = 48


def cylinder(a, b, r):
    """Closed cylinder from a to b (mm), r mm."""
    from manifold3d import Manifold

    a, b = np.asarray(a, float), np.asarray(b, float)
    d = b - a
    length = float(np.linalg.norm(d))
    z = d / length
    x = np.cross([0.0, 0.0, 1.0] if abs(z[2]) < 0.9 else [1.0, 0.0, 0.0], z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    m = np.column_stack([x, y, z, a])  # 3x4 affine
    return Manifold.cylinder(length, r, r, SEGMENTS).transform(m.tolist())


def build():
    from manifold3d import Manifold

    joints = {
        "hip": (0, 0, 0), "mid": (28, 0, 0), "neck": (56, 0, 0), "head": (66, 0, 0),
        "tail_tip": (-18, 0, -18), "l_leg": (12, 24, 0), "r_leg": (12, -24, 0),
        "l_arm": (44, 24, 0), "r_arm": (44, -24, 0),
        "l_hip": (12, 0, 0), "l_sh": (44, 0, 0),
    }
    parts = [
        cylinder((-1, 0, 0), (57, 0, 0), 3.5),  # spine
        cylinder((12, -24, 0), (12, 24, 0), 3.0),  # legs (hips)
        cylinder((44, -24, 0), (44, 24, 0), 3.0),  # arms (shoulders)
        cylinder((28, 0, 0), (28, 0, 10.5), 3.5),  # dorsal fin stub (no bone)
        cylinder((0.5, 0, 0.5), (-18, 0, -18), 2.5),  # tail
        Manifold.sphere(7.0, SEGMENTS).translate((63, 0, 0)),  # head
    ]
    body = parts[0]
    for p in parts[1:]:
        body = body + p
    # well-shaped triangles (edges <= 1.5 mm) so that gmsh meshes the FEM crops quickly
    mesh = body.refine_to_length(1.5).to_mesh()
    v = np.asarray(mesh.vert_properties)[:, :3].astype(np.float64)
    f = np.asarray(mesh.tri_verts).astype(np.int64)
    names = list(joints)
    j = np.array([joints[n] for n in names], float)
    k = {n: i for i, n in enumerate(names)}
    bones = [
        (k["hip"], k["l_hip"]), (k["l_hip"], k["mid"]), (k["mid"], k["l_sh"]),
        (k["l_sh"], k["neck"]), (k["neck"], k["head"]),
        (k["hip"], k["tail_tip"]),
        (k["l_hip"], k["l_leg"]), (k["l_hip"], k["r_leg"]),
        (k["l_sh"], k["l_arm"]), (k["l_sh"], k["r_arm"]),
    ]
    return v, f, j, bones


def main(out_dir):
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    v, f, j, bones = build()
    with open(out / "junction_rig.obj", "w") as fh:
        fh.writelines(f"v {p[0]:.9g} {p[1]:.9g} {p[2]:.9g}\n" for p in v)
        fh.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in f)
    write_tgf(out / "junction_rig.tgf", j, bones)
    print(f"{out / 'junction_rig.obj'}: {len(v)} vertices, {len(f)} faces, {len(bones)} bones")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
