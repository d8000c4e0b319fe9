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
