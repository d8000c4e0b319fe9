"""Options that several ``osteon`` commands share (the main parser and ``osteon batch``):
kept apart so that no command module imports another's parser. Units: mm, N, MPa."""

from __future__ import annotations

import argparse
import textwrap

from .. import materials, profiles

#: preset -> strength in MPa, from the one table in :mod:`osteon.materials`
MATERIALS = materials.strengths_mpa()
DEFAULT_SAFETY_FACTOR = materials.DEFAULT_SAFETY_FACTOR


def add_max_sections(p) -> None:
    """``--max-sections``: the global section budget (whole model, not per bone)."""
    from ..settings import MAX_SECTIONS

    p.add_argument(
        "--max-sections",
        type=int,
        default=None,
        metavar="N",
        help=f"refuse a model that would make more than N sections in all (default "
        f"{MAX_SECTIONS:,}, about 2 GB; the estimate and its memory are in the message)",
    )


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


def profile_list() -> str:
    """The print-profile presets, one per line with what they are and where their numbers come
    from (``--list-profiles``)."""
    lines = ["print profiles (--profile NAME; docs/printing.md):"]
    for key, prof in profiles.print_profiles().items():
        lines.append(f"  {key:<13} {prof.name}")
        lines.append(textwrap.fill(f"source: {prof.source}", 96, initial_indent=" " * 16,
                                   subsequent_indent=" " * 16))
    mats = ", ".join(f"{m.key} → {m.default_profile}" for m in materials.MATERIALS)
    lines.append(f"suggested per material: {mats}")
    return "\n".join(lines)


class ListProfiles(argparse.Action):
    """``--list-profiles``: print :func:`profile_list` and exit (like ``--version``)."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS,
                 help=None):
        super().__init__(option_strings, dest, nargs=0, default=default, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        print(profile_list())
        parser.exit()


def _percent(text) -> float:
    """``--infill``: a percentage 0…100 ("15" or "15%"), returned as a fraction 0…1."""
    raw = str(text).strip().rstrip("%").strip()
    try:
        v = float(raw)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a percentage 0-100, got {text!r}") from None
    if not (0.0 <= v <= 100.0):
        raise argparse.ArgumentTypeError(f"must be a percentage 0-100, got {text!r}")
    if 0.0 < v < 1.0:  # 0.15 is 0.15 %, almost surely meant as 15 %
        raise argparse.ArgumentTypeError(f"is a percentage: {text} means {v:g} %; "
                                         f"give {v * 100:g} for {v * 100:g} %")
    return v / 100.0


def add_print_options(p) -> None:
    """The print profile options (``Settings.print_profile`` and its overrides) on a command."""
    keys = list(profiles.print_profiles())
    g = p.add_argument_group(
        "print profile (walls, skins, infill; docs/printing.md)",
        "By default every section is analysed solid (the numbers of earlier versions). To "
        "analyse the part as a slicer prints it, give --profile (e.g. --profile prusaslicer: 2 "
        "perimeters, 15 % gyroid); the other options change one setting of it. "
        "--list-profiles lists the presets and their sources.")
    g.add_argument("--profile", choices=keys, default="solid", metavar="NAME",
                   help=f"print profile preset: {', '.join(keys)} (default solid)")
    g.add_argument("--list-profiles", action=ListProfiles,
                   help="list the print profiles with their sources and exit")
    g.add_argument("--perimeters", type=int, metavar="N",
                   help="FDM: wall loops per layer (count)")
    g.add_argument("--infill", type=_percent, metavar="PCT",
                   help="FDM: sparse infill density in percent, 0-100 (15 = 15 %%)")
    g.add_argument("--infill-pattern", choices=profiles.PATTERNS, metavar="NAME",
                   help=f"FDM: infill pattern: {', '.join(profiles.PATTERNS)}")
    g.add_argument("--line-width", type=float, metavar="MM",
                   help="FDM: perimeter extrusion width, mm")
    g.add_argument("--layer-height", type=float, metavar="MM", help="FDM: layer height, mm")
    g.add_argument("--top-bottom-layers", type=int, metavar="N",
                   help="FDM: solid layers at the top and bottom surfaces (count)")
    g.add_argument("--shell", type=float, metavar="MM",
                   help="hollowed resin (--profile resin_hollow): shell thickness, mm")
