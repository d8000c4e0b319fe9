"""Options that several ``osteon`` commands share (the main parser and ``osteon batch``):
kept apart so that no command module imports another's parser. Units: mm, N, MPa."""

from __future__ import annotations

from .. import materials

#: preset -> strength in MPa, from the one table in :mod:`osteon.materials`
MATERIALS = materials.strengths_mpa()
DEFAULT_SAFETY_FACTOR = materials.DEFAULT_SAFETY_FACTOR


def add_junction_switch(p) -> None:
    """``--no-junction-cores`` (``Settings.junctions``) on a command or an option group."""
    p.add_argument(
        "--no-junction-cores",
        dest="junction_cores",
        action="store_false",
        help="analyse whole cuts: skip the junction stage, which counts only the core that "
        "continues through the plane where a section cuts a side branch's stub "
        "(docs/junctions.md). Faster on models with many side branches, but a stub is then "
        "counted as carrying load (lower, unsafe stress there)",
    )


def add_notch_options(p) -> None:
    """``--notch-sensitivity Q`` and ``--min-notch-radius MM`` (``Settings.notch_sensitivity``,
    ``Settings.min_notch_radius_mm``; docs/notch.md) on a command or an option group."""
    p.add_argument(
        "--notch-sensitivity", type=float, default=None, metavar="Q",
        help="how much of a corner's stress peak the material feels, 0..1: the stress at a "
        "section next to a concave corner is (1 + Q (Kt - 1)) x the beam stress "
        "(default: the material's: 1 for PLA and resin, 0.5 for PETG, ABS, nylon)")
    p.add_argument(
        "--min-notch-radius", type=float, default=None, metavar="MM",
        help="sharpest inside corner the print makes, mm: sharper corners of the mesh are taken "
        "at this radius (default: the material's process: FDM 0.2, resin 0.05, SLS 0.1)")
