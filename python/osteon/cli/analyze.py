"""``osteon analyze``: section stresses, weak bones, the report and the picture."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .common import (
    _analyze,
    _check,
    _load,
    _png,
    _Progress,
    _report,
    _settings,
    _write_json,
    bone_table,
    format_table,
)


def analyze_model(model, settings, source):
    """Analyse a read model (``osteon.io.RiggedModel``, mm) with the settings
    (:class:`osteon.settings.Settings`) -> (Analysis, report dict, seconds). ``source`` names
    the model in the report (its file)."""
    a, secs = _analyze(settings, model)
    return a, _report(source, model, settings, a, secs), secs


def cmd_analyze(args, out):

    prog = _Progress(["reading model", "analysing", "writing outputs"], args.quiet)
    try:
        settings = _settings(args)
        _check(settings)
        material, allowable = settings.material_and_strength()[0], settings.allowable_stress_mpa()
        model = _load(args)
        prog.next()
        a, rep, secs = analyze_model(model, settings, args.model)
        prog.next()
        if args.json:
            _write_json(args.json, rep)
        if args.png:
            _png(
                args,
                model,
                a,
                allowable,
                title=f"{Path(args.model).name}: F = {args.force:g} N, {material} "
                f"[σ] = {allowable:g} MPa",
            )
        prog.next()
    finally:
        prog.close()
    if not args.quiet:
        print(
            f"{Path(args.model).name}: {len(model.vertices)} vertices, {len(model.faces)} "
            f"faces, {model.n_bones} bones, size {args.height_mm:g} mm",
            file=out,
        )
        print(
            f"{len(a.stress)} sections in {1000 * secs:.1f} ms; max stress "
            f"{a.max_stress:.2f} MPa; {int(np.sum(a.weak))} weak, {int(np.sum(a.culled))} "
            "culled (safe for sure)",
            file=out,
        )
        print(format_table(bone_table(a, args.top), allowable), file=out)
    return 0
