"""``osteon correct``: thicken weak bones until no section is weak; write the mesh in mm."""

from __future__ import annotations

import time
from pathlib import Path

from . import common


def cmd_correct(args, out):
    import osteon

    from ..io import write_mesh

    prog = common.Progress(["reading model", "correcting", "writing outputs"], args.quiet)
    try:
        settings = common.settings_from_args(args)
        common.check(settings, correct=True)
        allowable = settings.allowable_stress_mpa()
        if Path(args.out).suffix.lower() not in (".obj", ".off", ".ply", ".stl"):
            raise ValueError(f"--out {args.out}: use an .obj, .off, .ply or .stl file name")
        common.check_outputs(args, "out", "json", "png")
        model = common.load_model_of(args)
        common.print_warnings(model, args)
        prog.next()
        positional, keyword = common.engine_args(settings, model, correct=True,
                                                 max_sections=common.max_sections_of(args))
        t = time.perf_counter()
        fix = osteon.correct(*positional, **keyword)
        common.check_overflow(fix.before, keyword["force"])
        secs = time.perf_counter() - t
        prog.next()
        write_mesh(args.out, fix.vertices, model.faces)
        rounds = len(fix.rounds)
        if args.json:
            rep = common.report_of(args.model, model, settings, fix.before, secs, correction=fix,
                          output=args.out)
            common.write_json(args.json, rep)
        if args.png:
            common.save_png(
                args,
                model,
                fix.after,
                allowable,
                before=fix.before,
                vertices=fix.vertices,
                title=f"{common.display_name(args.model)} corrected: F = {args.force:g} N, "
                f"[σ] = {allowable:g} MPa",
            )
        prog.next()
    finally:
        prog.close()
    if not args.quiet:
        status = "converged" if fix.converged else "NOT converged"
        print(
            f"{common.display_name(args.model)}: max stress {fix.before.max_stress:.2f} -> "
            f"{fix.after.max_stress:.2f} MPa ([σ] = {allowable:g} MPa); {rounds} rounds, "
            f"{status} in {1000 * secs:.1f} ms",
            file=out,
        )
        print(common.profile_line(settings.profile().as_dict()), file=out)
        reason = fix.reason
        if reason and not fix.converged:
            print(f"why: {reason}", file=out)
        print(
            common.format_table(
                common.bone_table(fix.after, args.top, scales=fix.bone_scale), allowable, scales=True,
                layer_ratio=fix.after.layer_strength_ratio,
            ),
            file=out,
        )
        print(f"corrected mesh written to {args.out}", file=out)
    return 0 if fix.converged else 1
