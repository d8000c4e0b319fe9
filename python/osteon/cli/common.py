"""What the commands share: options -> settings, reading the model, running the engine, the
report, the terminal table, the picture, the progress bar. Units: mm, N, MPa."""

from __future__ import annotations

import os
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from .. import materials
from ..io.atomic import check_output_path, write_atomic
from ..io.model import printable
from ..report import bone_table as _bone_rows
from ..report import build_report, printable_stress, to_json, too_thin_mask
from ..settings import Settings, engine_arguments, min_thickness_mm


class CliError(Exception):
    pass


def settings_from_args(args) -> Settings:
    """The command's options as the shared :class:`osteon.settings.Settings`."""
    given = args.strength_mpa is not None
    return Settings(
        force_n=args.force,
        interval_mm=args.interval,
        material=materials.CUSTOM if given else args.material,
        strength_mpa=args.strength_mpa,
        safety_factor=args.safety_factor,
        held_bone=args.root,
        size_mode={"longest": "LARGEST", "z": "HEIGHT"}.get(args.axis, args.axis.upper()),
        print_size_mm=args.height_mm,
        max_scale=getattr(args, "max_scale", 3.0),
        max_rounds=getattr(args, "max_rounds", 100),
        scaling=getattr(args, "scaling", None) or _default_scaling(),
        build_direction=_build_direction(getattr(args, "build_direction", "0,0,1")),
        layer_strength_ratio=getattr(args, "layer_ratio", None),  # None: the material preset's
        junctions=getattr(args, "junction_cores", True),  # --no-junction-cores
        print_profile=getattr(args, "profile", "solid"),
        perimeters=getattr(args, "perimeters", None),
        infill=getattr(args, "infill", None),  # --infill is in percent, a fraction here
        infill_pattern=getattr(args, "infill_pattern", None),
        line_width_mm=getattr(args, "line_width", None),
        layer_height_mm=getattr(args, "layer_height", None),
        top_bottom_layers=getattr(args, "top_bottom_layers", None),
        shell_mm=getattr(args, "shell", None),
        notch_sensitivity=getattr(args, "notch_sensitivity", None),  # None: the material's
        min_notch_radius_mm=getattr(args, "min_notch_radius", None),
    )


def profile_line(profile: dict) -> str:
    """One line on the report's ``print_profile``: what the sections are."""
    if profile["kind"] == "solid":
        return ("sections as cut (solid); --profile NAME analyses them as printed "
                "(--list-profiles)")
    return f"sections as printed: {profile['name']}"


def _build_direction(text) -> tuple:
    try:
        d = tuple(float(x) for x in str(text).split(","))
    except ValueError:
        d = ()
    if len(d) != 3 or not np.all(np.isfinite(d)) or not np.linalg.norm(d) > 0:
        raise ValueError(f"--build-direction must be three numbers X,Y,Z, not all 0, got {text!r}")
    return d


def _default_scaling() -> str:
    import osteon

    return osteon.DEFAULT_SCALING


class Progress:
    """A stage bar on stderr (tqdm), silent when quiet or not a terminal."""

    def __init__(self, stages, quiet):
        self.bar = None
        if not quiet:
            try:
                from tqdm import tqdm

                self.bar = tqdm(
                    total=len(stages),
                    desc=stages[0],
                    unit="step",
                    leave=False,
                    disable=None,
                    file=sys.stderr,
                )
            except ImportError:
                self.bar = None
        self.stages = stages
        self.k = 0

    def next(self, note=None):
        self.k += 1
        if self.bar is not None:
            self.bar.update(1)
            if self.k < len(self.stages):
                self.bar.set_description(note or self.stages[self.k])

    def write(self, msg):
        if self.bar is not None:
            self.bar.set_description(msg[:60])

    def close(self):
        if self.bar is not None:
            self.bar.close()


def wants_auto_skeleton(args) -> bool:
    """``--skeleton auto``, or a mesh file with no skeleton given and no sidecar next to it."""
    if args.skeleton == "auto":
        return True
    if args.skeleton is not None or args.weights is not None:
        return False
    from ..io.loader import GLTF_EXTENSIONS, _sidecar

    p = Path(args.model)
    return (p.is_file() and p.suffix.lower() not in GLTF_EXTENSIONS
            and _sidecar(p, [".tgf", "_rig.txt"]) is None)


def auto_model_of(args, axis, root="centre"):
    """The mesh at its printed size (mm) with an :func:`osteon.auto_skeleton` rig; says so on
    stderr and in the model's notes."""
    from ..autoskeleton import auto_skeleton
    from ..io import read_mesh
    from ..io.model import RiggedModel

    v, f = read_mesh(args.model)
    m = RiggedModel(v, f, np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, np.int64), [],
                    source=str(args.model)).scaled_to(args.height_mm, axis)
    t = time.perf_counter()
    try:  # limbs thinner than the material prints get no bone
        min_t = min_thickness_mm(settings_from_args(args))
    except (AttributeError, ValueError):  # a command without the analysis's options
        material = getattr(args, "material", None)  # (osteon skeleton: --material only)
        min_t = None if material is None else materials.get(material).min_thickness_mm
    sk, w = auto_skeleton(m.vertices, m.faces, root=root, min_thickness=min_t)
    note = (f"skeleton: made by osteon.auto_skeleton ({sk.num_bones} bones in "
            f"{time.perf_counter() - t:.1f} s); no skeleton file was given or found")
    if not getattr(args, "quiet", False):
        print(f"osteon: {Path(args.model).name}: {note}", file=sys.stderr)
    return replace(m, heads=sk.heads, tails=sk.tails, parents=sk.parents.astype(np.int64),
                   bone_names=list(sk.names), weights=w, notes=[*m.notes, note])


def load_model_of(args):
    from ..io import load_model

    axis = None if args.axis == "longest" else args.axis
    if wants_auto_skeleton(args):
        return auto_model_of(args, axis)
    return load_model(
        args.model,
        skeleton=args.skeleton,
        weights=args.weights,
        height_mm=args.height_mm,
        axis=axis,
    )


def bone_table(analysis, top=10, scales=None):
    """Rows (worst first) of per-bone results (:func:`osteon.report.bone_table`)."""
    # too-thin sections are out of the max stress and the weak count: out of the rows too
    rows = _bone_rows(analysis.section_bone, printable_stress(analysis), analysis.weak,
                      analysis.bone_names, analysis.allowable_stress, scales,
                      analysis.stress_ratio, analysis.across_layers,
                      stress_concentration=getattr(analysis, "stress_concentration", None))
    return [r for r in rows if r["max_stress_mpa"] is not None][:top]


def format_table(rows, allowable, scales=False, layer_ratio=1.0):
    head = f"{'bone':<28} {'max σ MPa':>10} {'σ/[σ]':>7} {'weak':>9}"
    if scales:
        head += f" {'scale':>6}"
    lines = [head, "-" * len(head)]
    for r in rows:
        flag = "  WEAK" if r["ratio"] > 1 else ""
        if flag and layer_ratio != 1.0:
            flag += f" ({r['limit']})"
        line = (
            f"{r['bone'][:28]:<28} {r['max_stress_mpa']:>10.2f} {r['ratio']:>7.2f} "
            f"{r['weak_sections']:>4}/{r['sections']:<4}"
        )
        if scales:
            line += f" {r['scale']:>6.3f}"
        kt = r.get("stress_concentration")
        if kt is not None and kt > 1.0:  # the worst section is next to a corner (docs/notch.md)
            flag += f"  corner Kt {kt:.2f}"
        lines.append(line + flag)
    note = f"(allowable stress [σ] = {allowable:g} MPa"
    if layer_ratio != 1.0:
        note += (f" along layers, {layer_ratio * allowable:g} MPa across layers; "
                 "σ/[σ] uses each section's angle to the build direction")
    lines.append(note + ")")
    return "\n".join(lines)


#: the shared checks name a setting; the CLI names its option
_OPTIONS = {"force": "--force", "section interval": "--interval",
            "material strength": "--strength-mpa", "safety factor": "--safety-factor",
            "max scale": "--max-scale", "max rounds": "--max-rounds", "Held bone": "--root",
            "layer strength ratio": "--layer-ratio", "build direction": "--build-direction",
            # print profile (osteon.settings.resolve_profile, osteon.profiles.PrintProfile)
            "print profile": "--profile", "unknown print profile": "--profile",
            "perimeters": "--perimeters", "infill_pattern": "--infill-pattern",
            "infill": "--infill", "line_width": "--line-width",
            "layer_height": "--layer-height", "top_bottom_layers": "--top-bottom-layers",
            "shell": "--shell",
            "notch sensitivity": "--notch-sensitivity", "min notch radius": "--min-notch-radius"}


def _arguments(settings: Settings, bone_names, correct: bool) -> dict:
    try:
        return engine_arguments(settings, bone_names, correct=correct)
    except ValueError as e:
        msg = str(e)
        opt = next((o for w, o in _OPTIONS.items() if msg.startswith(w)), None)
        raise ValueError(f"{opt}: {msg}" if opt else msg) from None


def check(settings: Settings, correct: bool = False) -> None:
    """Check the settings before the model is read (the held bone is checked once it is)."""
    _arguments(replace(settings, held_bone=None), [], correct)


def engine_args(settings: Settings, model, correct: bool = False,
                max_sections: int | None = None) -> tuple[tuple, dict]:
    """The model and settings every command passes to the engine: (positional, keyword).
    Warns on stderr when they would make more than ``SECTION_LIMIT`` sections; refuses
    (ValueError with the estimate) above ``max_sections`` for the whole model (default
    :data:`osteon.settings.MAX_SECTIONS`)."""
    from ..settings import MAX_SECTIONS

    positional = (model.vertices, model.faces, model.skeleton, model.weights)
    keyword = _arguments(settings, model.bone_names, correct)
    warn_many_sections(model, keyword["interval"], max_sections)
    # the engine's own check of the budget (AnalysisOptions.max_sections) with the same limit
    keyword["max_sections"] = MAX_SECTIONS if max_sections is None else int(max_sections)
    return positional, keyword


def max_sections_of(args) -> int:
    """``--max-sections`` (the global section budget), or the default."""
    from ..settings import MAX_SECTIONS

    n = getattr(args, "max_sections", None)
    n = MAX_SECTIONS if n is None else int(n)
    if n < 1:
        raise ValueError(f"--max-sections must be >= 1, got {n}")
    return n


def print_warnings(model, args) -> None:
    """The reader's warnings (repaired weights, bones without weight) on stderr."""
    if getattr(args, "quiet", False):
        return
    for w in model.warnings:
        print(f"osteon: warning: {printable(w)}", file=sys.stderr)


def warn_many_sections(model, interval_mm: float, max_sections: int | None = None) -> str | None:
    """The section guard's warning (``osteon.settings.section_guard``) on stderr, if any;
    ValueError above the global budget (``osteon.settings.section_budget``)."""
    import numpy as np

    import osteon
    from osteon.settings import MAX_SECTIONS, section_budget, section_guard

    v = np.asarray(model.vertices)
    size = float(np.max(v.max(axis=0) - v.min(axis=0))) if len(v) else 0.0
    n = osteon.estimate_sections(model.skeleton, interval_mm)
    over = section_budget(n, len(v), interval_mm, size,
                          MAX_SECTIONS if max_sections is None else max_sections)
    if over:
        raise ValueError(f"{printable(model.source or 'model')}: refused: {over}")
    msg = section_guard(n, interval_mm, size)
    if msg:
        print(f"osteon: warning: {msg}; this may take long (Ctrl+C stops it)", file=sys.stderr)
    return msg


def run_analysis(settings: Settings, model, max_sections: int | None = None):
    """Run the analysis with the command's settings; returns (Analysis, seconds)."""
    import osteon

    positional, keyword = engine_args(settings, model, max_sections=max_sections)
    t = time.perf_counter()
    a = osteon.analyze(*positional, **keyword)
    check_overflow(a, keyword["force"])
    return a, time.perf_counter() - t


def check_overflow(analysis, force_n: float) -> None:
    """ValueError when the stresses overflowed floating point (a force like 1e308 N): an
    ``inf`` stress is no result, and reads as "could not be cut" further on."""
    stress = np.asarray(analysis.stress, dtype=np.float64)
    moment = np.asarray(analysis.moment, dtype=np.float64)
    n = int(np.count_nonzero(np.isinf(stress) | np.isinf(moment)))
    if n:
        raise ValueError(f"--force {force_n:g} N: {n} of {len(stress)} section stresses overflow "
                         "(inf); use a force a print can meet (newtons, e.g. 1 .. 1000)")


def headline(analysis, seconds: float) -> str:
    """The summary line: sections, max stress, weak, culled; the too-thin sections counted
    apart, so that it never contradicts the table."""
    thin = int(np.count_nonzero(too_thin_mask(analysis)))
    n = len(analysis.stress)
    text = f"{n} sections in {1000 * seconds:.1f} ms; "
    if thin == n and n:
        text += "no printable section (all too thin): no max stress"
    else:
        text += f"max stress {analysis.max_stress:.2f} MPa"
        if thin:
            text += f" over the {n - thin} printable sections"
    text += (f"; {int(np.sum(analysis.weak))} weak, {int(np.sum(analysis.culled))} culled "
             "(safe for sure)")
    if thin:
        text += f"; {thin} too thin to print (not counted, listed below)"
    return text


def report_of(source, model, settings: Settings, analysis, seconds, correction=None, output=None):
    """The one report (:func:`osteon.report.build_report`) of a model read from ``source``."""
    rep = build_report(
        analysis=analysis, bone_names=model.bone_names,
        allowable_mpa=settings.allowable_stress_mpa(), settings=settings.as_dict(),
        front_end="cli", model=printable(source), mm_per_unit=model.scale,
        vertices=len(model.vertices), faces=len(model.faces), seconds=seconds,
        correction=correction, output=output)
    # the reader's warnings (weights repaired, bones without weight, no skin) stay with the
    # numbers they qualify
    rep["warnings"] = [*rep.get("warnings", []), *(printable(w) for w in model.warnings)]
    return rep


def write_json(path, data):
    """The report as JSON, written atomically (a kill leaves the previous report whole)."""
    write_atomic(path, to_json(data))


def check_outputs(args, *options) -> None:
    """Check the output paths of the given options (``"json"``, ``"png"``, ``"out"``…) before
    the work: a folder, a missing folder or a read-only place is an error now, not after a
    long analysis."""
    for opt in options:
        value = getattr(args, opt.replace("-", "_"), None)
        if value:
            check_output_path(value, "--" + opt)


def display_name(path) -> str:
    """A file's name for titles and messages, undecodable bytes shown as U+FFFD."""
    return printable(Path(os.fspath(path)).name)


def save_png(args, model, analysis, allowable, before=None, vertices=None, marks=None, title="",
             orientation=None):
    from ..plots import save_stress_png

    write_atomic(args.png, writer=lambda tmp: save_stress_png(
        tmp,
        model.vertices if vertices is None else vertices,
        model.faces,
        analysis,
        model.heads,
        model.tails,
        model.parents,
        model.bone_names,
        allowable,
        title=printable(title),
        before=before,
        marks=marks,
        orientation=orientation,
        bones=any("auto_skeleton" in n for n in model.notes),
    ))
