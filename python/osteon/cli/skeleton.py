"""``osteon skeleton``: an automatic skeleton and weights for an unrigged mesh, written as
TGF + DMAT for reuse (``osteon analyze MODEL --skeleton OUT.tgf --weights OUT.dmat``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .. import materials
from . import common


def add_parser(sub):
    ps = sub.add_parser(
        "skeleton",
        help="make a skeleton and weights for an unrigged mesh (osteon.auto_skeleton)",
        description="Compute a bone skeleton and skinning weights for a closed mesh and write "
        "them as TGF + DMAT (in the mesh file's units, so that `osteon analyze MODEL "
        "--skeleton OUT.tgf --weights OUT.dmat` reuses them).",
    )
    ps.add_argument("model", help="closed mesh (OBJ/OFF/PLY/STL)")
    ps.add_argument("--out", required=True, metavar="FILE.tgf", help="skeleton file (TGF)")
    ps.add_argument("--weights-out", metavar="FILE.dmat",
                    help="weights file (DMAT; default: OUT with .dmat)")
    ps.add_argument("--root", choices=("centre", "base"), default="centre",
                    help="root at the bone nearest the barycentre (default) or at the base "
                    "(lowest point along +Z)")
    ps.add_argument("--height-mm", type=float, default=120.0,
                    help="printed size used for the skeleton's mm parameters (default 120)")
    ps.add_argument("--axis", default="longest", choices=("longest", "x", "y", "z"))
    ps.add_argument("--material", default=materials.DEFAULT_MATERIAL, metavar="NAME",
                    help="material preset whose minimum printable thickness decides which thin "
                    "limbs get bones: " + ", ".join(f"{m.key} {m.min_thickness_mm:g} mm"
                                                    for m in materials.MATERIALS)
                    + f" (default {materials.DEFAULT_MATERIAL})")
    ps.add_argument("-q", "--quiet", action="store_true")
    return ps


def cmd_skeleton(args, out):
    from ..io import write_dmat, write_tgf

    axis = None if args.axis == "longest" else args.axis
    m = common.auto_model_of(args, axis, root=args.root)
    pts = np.concatenate([m.heads, m.tails]) / m.scale  # back to the file's units
    key = np.round(pts * (1e6 / max(float(np.ptp(pts)), 1e-300))).astype(np.int64)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.ravel()
    b = len(m.heads)
    write_tgf(args.out, pts[first], np.column_stack([inverse[:b], inverse[b:]]))
    wpath = args.weights_out or str(Path(args.out).with_suffix(".dmat"))
    write_dmat(wpath, m.weights.toarray())
    if not args.quiet:
        print(f"{args.out}: {b} bones; {wpath}: {m.weights.shape[0]} x {b} weights", file=out)
    return 0
