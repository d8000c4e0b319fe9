"""``osteon analyze``: section stresses, weak bones, the report and the picture."""

from __future__ import annotations

from .. import doubt
from . import common, orient


def analyze_model(model, settings, source, max_sections=None):
    """Analyse a read model (``osteon.io.RiggedModel``, mm) with the settings
    (:class:`osteon.settings.Settings`) -> (Analysis, report dict, seconds). ``source`` names
    the model in the report (its file); ``max_sections``: the global budget (default
    :data:`osteon.settings.MAX_SECTIONS`)."""
    a, secs = common.run_analysis(settings, model, max_sections=max_sections)
    return a, common.report_of(source, model, settings, a, secs), secs


def cmd_analyze(args, out):

    prog = common.Progress(["reading model", "analysing", "writing outputs"], args.quiet)
    try:
        settings = common.settings_from_args(args)
        common.check(settings)
        common.check_outputs(args, "json", "png", "orient-out")
        material, allowable = settings.material_and_strength()[0], settings.allowable_stress_mpa()
        model = common.load_model_of(args)
        prog.next()
        common.print_warnings(model, args)
        a, rep, secs = analyze_model(model, settings, args.model,
                                     max_sections=common.max_sections_of(args))
        best = orient.best_orientation_of(args, model, a) if (args.orient or args.orient_out) \
            else None
        if best is not None:
            rep["orientation"] = orient.orientation_json(best)
        prog.next()
        if args.json:
            common.write_json(args.json, rep)
        if args.png:
            common.save_png(
                args,
                model,
                a,
                allowable,
                title=f"{common.display_name(args.model)}: F = {args.force:g} N, {material} "
                f"[σ] = {allowable:g} MPa",
                orientation=best,
            )
        prog.next()
    finally:
        prog.close()
    if not args.quiet:
        print(
            f"{common.display_name(args.model)}: {len(model.vertices)} vertices, {len(model.faces)} "
            f"faces, {model.n_bones} bones, size {args.height_mm:g} mm",
            file=out,
        )
        print(common.headline(a, secs), file=out)
        print(common.profile_line(rep["print_profile"]), file=out)
        doubt_text = doubt.analysis_text(a, model.bone_names)
        if doubt_text:
            print(f"NOT A CLEAN RESULT: {doubt_text}", file=out)
        print(common.format_table(common.bone_table(a, args.top), allowable,
                                  layer_ratio=a.layer_strength_ratio), file=out)
        _print_printability(rep, out)
        if best is not None:
            print("best print orientations:", file=out)
            print(orient.orientation_table(best), file=out)
            if args.orient_out:
                print(f"model turned to the best orientation written to {args.orient_out}",
                      file=out)
    return 0


def _print_printability(rep, out):
    """Too-thin sections, unreliable sections and loose pieces, apart from the overloaded."""
    thin = rep.get("too_thin_sections", [])
    if thin:
        print(f"{len(thin)} section(s) too thin to print (not corrected by scaling):", file=out)
        for t in thin[:10]:
            print(f"  {t['bone']} at {t['param_mm'] or 0:.1f} mm: {t['reason']}", file=out)
    doubt = rep.get("unreliable_sections", [])
    if doubt:
        print(f"{len(doubt)} unreliable section(s) (bone outside the mesh, no part of it there): "
              "left out of the results", file=out)
    for k, piece in enumerate(rep.get("loose_pieces", [])):
        print(f"loose piece {k + 1}: {piece['vertices']} vertices (from vertex "
              f"{piece['first_vertex']}) touch nothing held: it would fall off the print",
              file=out)
