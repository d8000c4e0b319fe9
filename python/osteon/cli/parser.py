"""The ``osteon`` command line: its options and help (mm, N, MPa in every option)."""

from __future__ import annotations

import argparse

from .. import materials
from .options import (
    DEFAULT_SAFETY_FACTOR,
    MATERIALS,
    ListProfiles,
    add_junction_switch,
    add_max_sections,
    add_notch_options,
    add_print_options,
)

__all__ = ["DEFAULT_SAFETY_FACTOR", "EXAMPLES", "MATERIALS", "add_junction_switch",
           "build_parser"]

EXAMPLES = """\
examples:
  osteon analyze arm.obj --skeleton arm.tgf --weights arm-weights.dmat --height-mm 120 \\
      --force 20 --material PLA --json report.json --png stress.png
  osteon analyze Fox.glb --height-mm 80 --material PETG --safety-factor 2
  osteon correct 2982_ori.obj --skeleton 2982_ori_rig.txt --force 30 --out fixed.obj
  osteon validate elephant.obj --skeleton elephant.tgf --fem --sections 4 --json fem.json

Model files: OBJ/OFF/PLY/STL with a TGF skeleton (+ DMAT weights) or a RigNet _rig.txt, or a
skinned glTF/GLB. Sidecar files next to the mesh (NAME.tgf, NAME.dmat, NAME-weights.dmat,
NAME_rig.txt) are found automatically.
"""


def _add_common(p: argparse.ArgumentParser):
    g = p.add_argument_group("model")
    g.add_argument("model", help="mesh (OBJ/OFF/PLY/STL) or skinned glTF/GLB file")
    g.add_argument(
        "--skeleton",
        metavar="FILE",
        help="skeleton: libigl TGF or RigNet _rig.txt, or 'auto' (osteon.auto_skeleton); "
        "default: sidecar next to MODEL, else auto",
    )
    g.add_argument(
        "--weights",
        metavar="FILE",
        help="skinning weights, DMAT (columns = TGF bones); default: sidecar, else "
        "each vertex is bound to its nearest bone",
    )
    g.add_argument(
        "--height-mm",
        type=float,
        default=120.0,
        metavar="MM",
        help="printed size in mm of the model's largest bounding-box side (default 120)",
    )
    g.add_argument(
        "--axis",
        choices=["longest", "x", "y", "z"],
        default="longest",
        help="which model extent --height-mm sets (default: longest)",
    )
    a = p.add_argument_group("loads and material")
    a.add_argument(
        "--force",
        type=float,
        default=20.0,
        metavar="N",
        help="force in newtons on the worst point of each branch (default 20)",
    )
    a.add_argument(
        "--material",
        default=materials.DEFAULT_MATERIAL,
        metavar="NAME",
        help="material preset: "
        + ", ".join(f"{k} {v:g} MPa" for k, v in MATERIALS.items())
        + " (default PLA)",
    )
    a.add_argument(
        "--strength-mpa",
        type=float,
        metavar="MPA",
        help="material strength in MPa (overrides the preset)",
    )
    a.add_argument(
        "--safety-factor",
        type=float,
        default=DEFAULT_SAFETY_FACTOR,
        metavar="K",
        help=f"allowable stress = strength / K (default {DEFAULT_SAFETY_FACTOR:g}; "
        "see osteon/materials.py)",
    )
    a.add_argument(
        "--interval",
        type=float,
        default=2.0,
        metavar="MM",
        help="distance in mm between sections along each bone (default 2)",
    )
    a.add_argument(
        "--root",
        metavar="BONE",
        help="bone (name or index) held at its head (default: the main root bone)",
    )
    add_max_sections(a)
    pr = p.add_argument_group("print direction (FDM layers; docs/printing.md)")
    pr.add_argument(
        "--build-direction",
        default="0,0,1",
        metavar="X,Y,Z",
        help="build (layer stacking) direction in the model's frame (default 0,0,1: +Z)",
    )
    pr.add_argument(
        "--layer-ratio",
        type=float,
        metavar="R",
        help="layer / in-plane strength (default: the material preset's, e.g. PLA 0.55; "
        "1 with --strength-mpa)",
    )
    add_print_options(p)
    o = p.add_argument_group("output")
    o.add_argument("--json", metavar="FILE", help="write a JSON report")
    o.add_argument("--png", metavar="FILE", help="write a PNG of the stress map and chain plot")
    o.add_argument(
        "--top",
        type=int,
        default=10,
        metavar="K",
        help="bones listed in the terminal table (default 10)",
    )
    o.add_argument("-q", "--quiet", action="store_true", help="no table, no progress bars")


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="osteon",
        description="Find the parts of a rigged 3D model that will break once printed, and "
        "thicken them (skeleton-sectional analysis; mm, N, MPa).",
        epilog=EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--version", action="version", version=f"osteon {_version()}")
    p.add_argument("--list-profiles", action=ListProfiles,
                   help="list the print profiles (--profile) with their sources and exit")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", required=True)
    pa = sub.add_parser(
        "analyze",
        help="section stresses, weak bones, report and picture",
        description="Analyse a rigged model: stress in every section along the "
        "bones under a force on each branch, held at the root.",
    )
    _add_common(pa)
    add_junction_switch(pa)
    add_notch_options(pa)
    po = pa.add_argument_group("best print orientation (docs/printing.md)")
    po.add_argument(
        "--orient",
        action="store_true",
        help="search the build directions for the one with the lowest worst stress ratio and "
        "print the best few",
    )
    po.add_argument(
        "--orient-out",
        metavar="FILE",
        help="write the model turned so that the best direction is +Z (OBJ/OFF/PLY/STL, mm); "
        "implies --orient",
    )
    po.add_argument(
        "--orient-samples",
        type=int,
        default=4000,
        metavar="N",
        help="directions on the sphere before local refinement (default 4000)",
    )
    po.add_argument(
        "--orient-flat",
        action="store_true",
        help="only orientations resting on a flat face of the convex hull",
    )
    pc = sub.add_parser(
        "correct",
        help="thicken weak bones until no section is weak",
        description="Analyse, then scale the cross-sections of weak bones "
        "(their length kept) and write the corrected mesh in mm.",
    )
    _add_common(pc)
    add_junction_switch(pc)
    add_notch_options(pc)
    pc.add_argument(
        "--out",
        metavar="FILE",
        required=True,
        help="corrected mesh (OBJ/OFF/PLY/STL), in mm at the printed size",
    )
    pc.add_argument(
        "--max-scale",
        type=float,
        default=3.0,
        metavar="S",
        help="largest cross-section scale per bone (default 3)",
    )
    pc.add_argument(
        "--max-rounds", type=int, default=100, metavar="N", help="most scaling rounds (default 100)"
    )
    pc.add_argument(
        "--scaling",
        choices=("thin", "uniform"),
        default=None,
        help="thin: flat parts are thickened across their thickness only (keeps widths, adds "
        "less material); uniform: both axes across the bone, as in the paper (default: "
        "osteon.DEFAULT_SCALING)",
    )
    pv = sub.add_parser(
        "validate",
        help="check the input; with --fem compare with a FEM solve",
        description="Check the model (closed mesh, weights, bones inside); with "
        "--fem cross-check section stresses with gmsh + CalculiX.",
    )
    _add_common(pv)
    add_notch_options(pv)
    pv.add_argument(
        "--fem",
        action="store_true",
        help="run the FEM cross-check (needs the gmsh and ccx programs)",
    )
    pv.add_argument(
        "--sections",
        type=int,
        default=4,
        metavar="N",
        help="sections tested with FEM, at most one per bone (default 4)",
    )
    pv.add_argument(
        "--junctions",
        action="store_true",
        help="with --fem: test junction sections (a side branch cut, only the core counted; "
        "docs/junctions.md) instead of plain ones",
    )
    pv.add_argument(
        "--notch",
        action="store_true",
        help="with --fem: test sections flagged notch (a corner, docs/notch.md) instead of "
        "plain ones",
    )
    pv.add_argument(
        "--section",
        action="append",
        metavar="ID",
        help="with --fem: test this section, flagged or not: N (its index, as in the JSON's "
        "section table) or BONE:N (checked to lie on BONE); repeatable; replaces the picking",
    )
    pv.add_argument(
        "--fem-fine",
        type=float,
        default=3.0,
        metavar="K",
        help="with --fem: element size r/K within 3 r of each tested section (default 3; 6 "
        "to check the mesh's convergence)",
    )
    pv.add_argument(
        "--mesh-size",
        type=float,
        metavar="MM",
        help="FEM element size away from the tested sections, mm "
        "(default: 1/40 of the model's diagonal)",
    )
    pv.add_argument(
        "--threads",
        type=int,
        default=2,
        metavar="N",
        help="threads for gmsh and CalculiX (default 2)",
    )
    from .reinforce import add_parser as _add_reinforce

    _add_reinforce(sub, _add_common)
    from .skeleton import add_parser as _add_skeleton

    _add_skeleton(sub)
    from .batch import add_batch_parser

    add_batch_parser(sub)
    return p


def _version():
    try:
        from importlib.metadata import version

        return version("osteon")
    except Exception:  # noqa: BLE001 - not installed as a distribution
        return "unknown"
