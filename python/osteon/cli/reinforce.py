"""``osteon reinforce``: more walls and denser infill where the printed part is weak, written
as a slicer project (3MF with modifier volumes) instead of a reshaped mesh. mm, N, MPa."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from . import common


def add_parser(sub, add_common) -> None:
    """The ``reinforce`` command on ``sub``; ``add_common``: the commands' shared options
    (``parser._add_common``, passed in: this module does not import the parser)."""
    from .options import add_junction_switch

    p = sub.add_parser(
        "reinforce",
        help="more walls / infill where the print is weak: a slicer project (3MF)",
        description="Analyse the part as printed with --profile, give each weak region the "
        "fewest extra walls (then denser infill, up to solid) that make it hold, and write a "
        "3MF with the model and one modifier volume per region (docs/correction.md).",
    )
    add_common(p)
    add_junction_switch(p)
    if "--profile" not in p._option_string_actions:  # the common print options add it
        p.add_argument("--profile", default="prusaslicer", metavar="NAME",
                       help="print profile preset (osteon.profiles.print_profiles)")
    p.add_argument("--out", metavar="FILE", required=True,
                   help="slicer project to write (.3mf)")
    p.add_argument("--slicer", choices=("prusaslicer", "bambu", "orca"), default="prusaslicer",
                   help="project format: PrusaSlicer, Bambu Studio or OrcaSlicer "
                   "(default prusaslicer)")
    p.add_argument("--max-perimeters", type=int, default=10, metavar="N",
                   help="most walls a region gets before its infill is raised (default 10)")
    p.add_argument("--margin", type=float, default=1.0, metavar="MM",
                   help="how far each modifier volume reaches beyond its sections, mm "
                   "(default 1)")


def _profile(args, settings, keyword):
    """The print profile: the shared settings' (with the print options) or ``--profile``."""
    from ..profiles import get_profile

    given = keyword.pop("print_profile", None)
    if given is not None:
        return given
    resolve = getattr(settings, "profile", None)
    profile = resolve() if resolve is not None else get_profile(args.profile)
    if profile.kind != "fdm":
        raise ValueError(f"--profile: reinforce needs an FDM profile (walls and infill), "
                         f"{profile.name!r} is {profile.kind}; e.g. --profile prusaslicer")
    return profile


def cmd_reinforce(args: argparse.Namespace, out) -> int:
    import osteon

    prog = common.Progress(["reading model", "reinforcing", "writing outputs"], args.quiet)
    try:
        settings = common.settings_from_args(args)
        common.check(settings)
        if Path(args.out).suffix.lower() != ".3mf":
            raise ValueError(f"--out {args.out}: use a .3mf file name")
        model = common.load_model_of(args)
        prog.next()
        positional, keyword = common.engine_args(settings, model)
        profile = _profile(args, settings, keyword)
        t = time.perf_counter()
        r = osteon.reinforce(*positional, print_profile=profile,
                             max_perimeters=args.max_perimeters, margin=args.margin, **keyword)
        secs = time.perf_counter() - t
        prog.next()
        r.write_3mf(args.out, slicer=args.slicer, name=Path(args.model).stem)
        if args.json:
            from ..report import reinforcement_section

            rep = common.report_of(args.model, model, settings, r.before, secs,
                                   output=args.out)
            rep["reinforcement"] = reinforcement_section(r, args.slicer, args.out)
            common.write_json(args.json, rep)
        if args.png:
            common.save_png(args, model, r.after, settings.allowable_stress_mpa(),
                            before=r.before, title=f"{Path(args.model).name} reinforced: "
                            f"{len(r.regions)} region(s), {profile.name}")
        prog.next()
    finally:
        prog.close()
    if not args.quiet:
        print(format_regions(r, Path(args.model).name), file=out)
        print(f"slicer project ({args.slicer}) written to {args.out}", file=out)
    return 0 if not r.unfixable else 1


def format_regions(r, name: str) -> str:
    """The terminal table of a reinforcement: one line per region."""
    p = r.profile
    lines = [(f"{name}: {len(r.regions)} weak region(s) under {p.name} ({p.perimeters} walls, "
             f"{100 * p.infill:.0f} % infill); max stress {r.before.max_stress:.2f} -> "
             f"{r.after.max_stress:.2f} MPa ([σ] = {r.before.allowable_stress:g} MPa), "
             f"+{r.extra_volume_mm3:.0f} mm³ of filament")]
    head = f"{'bone':<24} {'walls':>7} {'infill %':>9} {'σ MPa before → after':>22} {'+mm³':>7}"
    lines += [head, "-" * len(head)]
    for g in r.regions:
        lines.append(
            f"{g['bone'][:24]:<24} {g['perimeters_before']:>3}→{g['perimeters']:<3} "
            f"{100 * g['infill_before']:>4.0f}→{100 * g['infill']:<4.0f} "
            f"{g['stress_before_mpa']:>10.2f} → {g['stress_after_mpa']:<9.2f} "
            f"{g['extra_volume_mm3']:>7.0f}" + ("" if g["fixed"] else "  solid is not enough"))
    if r.unfixable:
        bones = sorted({u["bone"] for u in r.unfixable})
        lines.append(f"{len(r.unfixable)} section(s) even solid cannot carry (bones: "
                     f"{', '.join(bones)}): thicken them (osteon correct)")
    return "\n".join(lines)
