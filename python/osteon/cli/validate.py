"""``osteon validate``: input checks and, with ``--fem``, the FEM cross-check."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from ..report import finite
from . import common


def cmd_validate(args, out):

    stages = ["reading model", "analysing"] + (["meshing + solving (FEM)"] if args.fem else [])
    prog = common.Progress(stages + ["writing outputs"], args.quiet)
    try:
        settings = common.settings_from_args(args)
        common.check(settings)
        if args.fem and not settings.profile().is_solid:
            # the FEM mesh is the solid part: its stresses are not those of printed walls
            raise ValueError("--fem checks the solid part against FEM: use it without "
                             "--profile (or --profile solid)")
        common.check_outputs(args, "json", "png")
        check_fem_options(args)
        allowable = settings.allowable_stress_mpa()
        model = common.load_model_of(args)
        common.print_warnings(model, args)
        checks = model_checks(model)
        prog.next()
        a, secs = common.run_analysis(settings, model,
                                      max_sections=common.max_sections_of(args))
        prog.next()
        rep = {
            "model": str(args.model),
            "checks": checks,
            "analysis_seconds": secs,
            "max_stress_mpa": finite(a.max_stress),
            "allowable_stress_mpa": allowable,
            "force_n": args.force,
            "sections": len(a.stress),
        }
        fem_rep = None
        if args.fem:
            from .. import fem

            if not checks["watertight"]:
                raise ValueError(f"{args.model}: the mesh is not closed; FEM needs a closed mesh")
            secs_list = fem_sections(args, a, model)
            missing = fem.missing_tools_message("--fem")
            if missing is not None:
                raise ValueError(missing)
            t = time.perf_counter()
            fem_rep = fem.cross_check(
                model.vertices,
                model.faces,
                secs_list,
                force=args.force,
                hold_point=fem.hold_point(a, model.heads),
                mesh_size=args.mesh_size,
                threads=args.threads,
                progress=prog.write,
                fine_factor=args.fem_fine,
            )
            rep["fem"] = fem_rep.as_dict()
            for row in rep["fem"]["sections"] + rep["fem"]["failed_sections"]:
                row["bone_name"] = model.bone_names[row["bone"]] if row["bone"] >= 0 else None
            rep["fem"]["seconds"] = time.perf_counter() - t
            prog.next()
        if args.json:
            common.write_json(args.json, rep)
        if args.png:
            marks = None if fem_rep is None else [s.center for s in fem_rep.sections]
            common.save_png(
                args,
                model,
                a,
                allowable,
                marks=marks,
                title=f"{common.display_name(args.model)}: F = {args.force:g} N",
            )
            if fem_rep is not None:
                from ..plots import save_fem_png

                p = Path(args.png)
                common.write_atomic(p.with_name(p.stem + "_fem" + p.suffix),
                                    writer=lambda tmp: save_fem_png(tmp, fem_rep))
        prog.next()
    finally:
        prog.close()
    if not args.quiet:
        for k, v in checks.items():
            print(f"{k:<24} {v}", file=out)
        print(f"analysis: {len(a.stress)} sections in {1000 * secs:.1f} ms", file=out)
        if fem_rep is not None:
            print(format_fem_table(fem_rep, a.bone_names), file=out)
    return 0


def check_fem_options(args):
    """One-line errors for FEM options that do not go together."""
    chosen = getattr(args, "section", None)
    junctions, notch = getattr(args, "junctions", False), getattr(args, "notch", False)
    if (chosen or junctions or notch) and not args.fem:
        raise ValueError("--section, --junctions and --notch choose the FEM check's sections: "
                         "use them with --fem")
    if chosen and (junctions or notch):
        raise ValueError("--section chooses the sections itself: not with --junctions or --notch")
    if junctions and notch:
        raise ValueError("--junctions and --notch pick different sections: one at a time")
    fine = getattr(args, "fem_fine", 3.0)
    if not (np.isfinite(fine) and 1.0 <= fine <= 20.0):
        raise ValueError(f"--fem-fine must be between 1 and 20, got {fine:g}")


def fem_sections(args, a, model):
    """The sections the FEM check tests: the chosen ones (``--section``), else picked."""
    from .. import fem

    chosen = getattr(args, "section", None)
    if chosen:
        return fem.chosen_sections(a, fem.parse_section_ids(chosen, list(a.bone_names)))
    # junctions and corners sit near joints by nature: any distance from the bone's ends
    junctions = getattr(args, "junctions", False)
    notch = getattr(args, "notch", False)
    tiers = ((0.0, 2.0),) if junctions or notch else ((1.5, 3.0), (0.75, 2.0))
    secs_list = fem.pick_sections(a, model.heads, model.tails, n=args.sections, tiers=tiers,
                                  junctions=junctions, notch=notch)
    if not secs_list:
        why = (", or no junction section with its load point >= 2 r off the plane)" if junctions
               else ", or no notch section with its load point >= 2 r off the plane)" if notch
               else ")")
        raise ValueError("no section suitable for the FEM check (all near joints, the held "
                         "region, too stubby" + why)
    return secs_list


def format_fem_table(rep, bone_names):
    head = (f"{'#':>2} {'sec':>4} {'bone':<18} {'arm mm':>7} {'Kt':>5} {'osteon MPa':>11} "
            f"{'FEM MPa':>9} {'error':>7} {'corner':>8} {'error':>7}")
    lines = [head, "-" * len(head)]
    for i, s in enumerate(rep.sections, 1):
        name = bone_names[s.bone] if 0 <= s.bone < len(bone_names) else str(s.bone)
        peak = float(s.extra.get("fem_corner_peak_mpa", float("nan")))
        corner = (f"{peak:>8.2f} {100 * (s.osteon_stress_mpa - peak) / peak:>+6.1f}%"
                  if np.isfinite(peak) and peak > 0 else f"{'—':>8} {'':>7}")
        lines.append(
            f"{i:>2} {s.index:>4} {name[:18]:<18} {s.moment_arm_mm:>7.1f} "
            f"{s.extra.get('stress_concentration', 1.0):>5.2f} {s.osteon_stress_mpa:>11.2f} "
            f"{s.fem_stress_mpa:>9.2f} {100 * s.rel_error:>+6.1f}% {corner}"
        )
    lines.append("FEM = the worst σ_nn on the section's plane; corner = the largest principal "
                 "stress within one interval of it (docs/validation.md); error = (osteon − FEM) "
                 "/ FEM")
    for f in rep.failed:
        name = bone_names[f["bone"]] if 0 <= f["bone"] < len(bone_names) else str(f["bone"])
        lines.append(f" - {name[:22]:<22} FEM failed: {f['reason'][:60]}")
    errors = (
        f"median |error| {100 * rep.median_error:.1f} %, worst {100 * rep.worst_error:.1f} %"
        if rep.sections
        else f"no section could be checked ({len(rep.failed)} failed)"
    )
    lines.append(
        f"{errors}; FEM {rep.nodes} nodes, {rep.elements} C3D10 tets, mesh "
        f"{rep.mesh_seconds:.1f} s + solve {rep.solve_seconds:.1f} s"
    )
    return "\n".join(lines)


def weight_text(found: dict) -> str:
    """What the reader found in the file's weights, in words ("clean" when nothing)."""
    if not found:
        return "not checked (no per-entry weights in the file)"
    parts = []
    if found.get("nonfinite"):
        parts.append(f"{found['nonfinite']} NaN/inf entries set to 0")
    if found.get("negative"):
        parts.append(f"{found['negative']} negative entries set to 0")
    if found.get("rows_far_from_1"):
        parts.append(f"{found['rows_far_from_1']} rows summed to {found['row_sum_min']:.3g} .. "
                     f"{found['row_sum_max']:.3g}, rescaled to 1")
    return "; ".join(parts) if parts else "clean (every weighted row sums to 1)"


def model_checks(model):
    """Cheap input checks: closed mesh, pieces, weights, bones inside the bounding box."""
    import trimesh

    m = trimesh.Trimesh(model.vertices, model.faces, process=False)
    res = {
        "vertices": len(model.vertices),
        "faces": len(model.faces),
        "bones": model.n_bones,
        "watertight": bool(m.is_watertight),
        "pieces": int(m.body_count),
        "size_mm": [round(float(x), 3) for x in model.vertices.max(0) - model.vertices.min(0)],
    }
    if model.weights is not None:
        s = np.asarray(model.weights.sum(axis=1)).ravel()
        res["unweighted_vertices"] = int(np.sum(s == 0))
        # what the file held, before the reader cleaned it (the cleaned rows always sum to 1)
        found = model.weight_findings
        res["weight_rows_sum_to_1"] = not found.get("rows_far_from_1", 0)
        res["weights_in_file"] = weight_text(found)
        bare = [n for n, c in zip(model.bone_names,
                                  np.asarray(model.weights.sum(axis=0)).ravel()) if c == 0]
        res["bones_without_weight"] = ", ".join(bare) if bare else 0
    else:
        res["weights"] = "none (nearest bone)"
    return res
