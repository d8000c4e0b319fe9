"""The ``osteon`` command: analyse, correct and validate rigged models from files.

Units everywhere: millimetres of the printed object, newtons, MPa.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from . import materials
from .report import bone_table as _bone_rows
from .report import build_report, finite, to_json
from .settings import Settings, engine_arguments

#: preset -> strength in MPa, from the one table in :mod:`osteon.materials`
MATERIALS = materials.strengths_mpa()
DEFAULT_SAFETY_FACTOR = materials.DEFAULT_SAFETY_FACTOR

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


class CliError(Exception):
    pass


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
    sub = p.add_subparsers(dest="command", metavar="COMMAND", required=True)
    pa = sub.add_parser(
        "analyze",
        help="section stresses, weak bones, report and picture",
        description="Analyse a rigged model: stress in every section along the "
        "bones under a force on each branch, held at the root.",
    )
    _add_common(pa)
    pc = sub.add_parser(
        "correct",
        help="thicken weak bones until no section is weak",
        description="Analyse, then scale the cross-sections of weak bones "
        "(their length kept) and write the corrected mesh in mm.",
    )
    _add_common(pc)
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
    ps = sub.add_parser(
        "skeleton",
        help="make a skeleton and weights for an unrigged mesh (osteon.auto_skeleton)",
        description="Compute a bone skeleton and skinning weights for a closed mesh and write "
        "them as TGF + DMAT (in the mesh file's units, so that `osteon analyze MODEL "
        "--skeleton OUT.tgf --weights OUT.dmat` reuses them).",
    )
    ps.add_argument("model", help="closed mesh (OBJ/OFF/PLY/STL)")
    ps.add_argument("--out", required=True, metavar="FILE.tgf", help="skeleton file (TGF)")
    ps.add_argument("--weights-out", metavar="FILE.dmat",
                    help="weights file (DMAT; default: OUT with .dmat)")
    ps.add_argument("--root", choices=("centre", "base"), default="centre",
                    help="root at the bone nearest the barycentre (default) or at the base "
                    "(lowest point along +Z)")
    ps.add_argument("--height-mm", type=float, default=120.0,
                    help="printed size used for the skeleton's mm parameters (default 120)")
    ps.add_argument("--axis", default="longest", choices=("longest", "x", "y", "z"))
    ps.add_argument("-q", "--quiet", action="store_true")
    return p


def cmd_skeleton(args, out):
    from .io import write_dmat, write_tgf

    axis = None if args.axis == "longest" else args.axis
    args.skeleton = args.weights = None
    m = _auto_model(args, axis)
    pts = np.concatenate([m.heads, m.tails]) / m.scale  # back to the file's units
    key = np.round(pts * (1e6 / max(float(np.ptp(pts)), 1e-300))).astype(np.int64)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.ravel()
    b = len(m.heads)
    write_tgf(args.out, pts[first], np.column_stack([inverse[:b], inverse[b:]]))
    wpath = args.weights_out or str(Path(args.out).with_suffix(".dmat"))
    write_dmat(wpath, m.weights.toarray())
    if not args.quiet:
        print(f"{args.out}: {b} bones; {wpath}: {m.weights.shape[0]} x {b} weights", file=out)
    return 0


def _version():
    try:
        from importlib.metadata import version

        return version("osteon")
    except Exception:  # noqa: BLE001 - not installed as a distribution
        return "unknown"


def _settings(args) -> Settings:
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
    )


def _default_scaling() -> str:
    import osteon

    return osteon.DEFAULT_SCALING


class _Progress:
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


def _wants_auto_skeleton(args) -> bool:
    """``--skeleton auto``, or a mesh file with no skeleton given and no sidecar next to it."""
    if args.skeleton == "auto":
        return True
    if args.skeleton is not None or args.weights is not None:
        return False
    from .io.loader import GLTF_EXTENSIONS, _sidecar

    p = Path(args.model)
    return (p.is_file() and p.suffix.lower() not in GLTF_EXTENSIONS
            and _sidecar(p, [".tgf", "_rig.txt"]) is None)


def _auto_model(args, axis):
    """The mesh at its printed size with an :func:`osteon.auto_skeleton` rig."""
    from .autoskeleton import auto_skeleton
    from .io import read_mesh
    from .io.model import RiggedModel

    v, f = read_mesh(args.model)
    m = RiggedModel(v, f, np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, np.int64), [],
                    source=str(args.model)).scaled_to(args.height_mm, axis)
    t = time.perf_counter()
    sk, w = auto_skeleton(m.vertices, m.faces, root=getattr(args, "root", "centre") or "centre")
    note = (f"skeleton: made by osteon.auto_skeleton ({sk.num_bones} bones in "
            f"{time.perf_counter() - t:.1f} s); no skeleton file was given or found")
    if not getattr(args, "quiet", False):
        print(f"osteon: {Path(args.model).name}: {note}", file=sys.stderr)
    return replace(m, heads=sk.heads, tails=sk.tails, parents=sk.parents.astype(np.int64),
                   bone_names=list(sk.names), weights=w, notes=[*m.notes, note])


def _load(args):
    from .io import load_model

    axis = None if args.axis == "longest" else args.axis
    if _wants_auto_skeleton(args):
        return _auto_model(args, axis)
    return load_model(
        args.model,
        skeleton=args.skeleton,
        weights=args.weights,
        height_mm=args.height_mm,
        axis=axis,
    )


def bone_table(analysis, top=10, scales=None):
    """Rows (worst first) of per-bone results (:func:`osteon.report.bone_table`)."""
    rows = _bone_rows(analysis.section_bone, analysis.stress, analysis.weak,
                      analysis.bone_names, analysis.allowable_stress, scales)
    return [r for r in rows if r["max_stress_mpa"] is not None][:top]


def format_table(rows, allowable, scales=False):
    head = f"{'bone':<28} {'max σ MPa':>10} {'σ/[σ]':>7} {'weak':>9}"
    if scales:
        head += f" {'scale':>6}"
    lines = [head, "-" * len(head)]
    for r in rows:
        flag = "  WEAK" if r["ratio"] > 1 else ""
        line = (
            f"{r['bone'][:28]:<28} {r['max_stress_mpa']:>10.2f} {r['ratio']:>7.2f} "
            f"{r['weak_sections']:>4}/{r['sections']:<4}"
        )
        if scales:
            line += f" {r['scale']:>6.3f}"
        lines.append(line + flag)
    lines.append(f"(allowable stress [σ] = {allowable:g} MPa)")
    return "\n".join(lines)


#: the shared checks name a setting; the CLI names its option
_OPTIONS = {"force": "--force", "section interval": "--interval",
            "material strength": "--strength-mpa", "safety factor": "--safety-factor",
            "max scale": "--max-scale", "max rounds": "--max-rounds", "Held bone": "--root"}


def _arguments(settings: Settings, bone_names, correct: bool) -> dict:
    try:
        return engine_arguments(settings, bone_names, correct=correct)
    except ValueError as e:
        msg = str(e)
        opt = next((o for w, o in _OPTIONS.items() if msg.startswith(w)), None)
        raise ValueError(f"{opt}: {msg}" if opt else msg) from None


def _check(settings: Settings, correct: bool = False) -> None:
    """Check the settings before the model is read (the held bone is checked once it is)."""
    _arguments(replace(settings, held_bone=None), [], correct)


def _engine_args(settings: Settings, model, correct: bool = False) -> tuple[tuple, dict]:
    """The model and settings every command passes to the engine: (positional, keyword)."""
    positional = (model.vertices, model.faces, model.skeleton, model.weights)
    return positional, _arguments(settings, model.bone_names, correct)


def _analyze(settings: Settings, model):
    """Run the analysis with the command's settings; returns (Analysis, seconds)."""
    import osteon

    positional, keyword = _engine_args(settings, model)
    t = time.perf_counter()
    a = osteon.analyze(*positional, **keyword)
    return a, time.perf_counter() - t


def _report(args, model, settings: Settings, analysis, seconds, correction=None):
    return build_report(
        analysis=analysis, bone_names=model.bone_names,
        allowable_mpa=settings.allowable_stress_mpa(), settings=settings.as_dict(),
        front_end="cli", model=str(args.model), mm_per_unit=model.scale,
        vertices=len(model.vertices), faces=len(model.faces), seconds=seconds,
        correction=correction, output=getattr(args, "out", None))


def _write_json(path, data):
    Path(path).write_text(to_json(data))


def _png(args, model, analysis, allowable, before=None, vertices=None, marks=None, title=""):
    from .plots import save_stress_png

    save_stress_png(
        args.png,
        model.vertices if vertices is None else vertices,
        model.faces,
        analysis,
        model.heads,
        model.tails,
        model.parents,
        model.bone_names,
        allowable,
        title=title,
        before=before,
        marks=marks,
        bones=any("auto_skeleton" in n for n in model.notes),
    )


def cmd_analyze(args, out):

    prog = _Progress(["reading model", "analysing", "writing outputs"], args.quiet)
    try:
        settings = _settings(args)
        _check(settings)
        material, allowable = settings.material_and_strength()[0], settings.allowable_stress_mpa()
        model = _load(args)
        prog.next()
        a, secs = _analyze(settings, model)
        prog.next()
        rep = _report(args, model, settings, a, secs)
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


def cmd_correct(args, out):
    import osteon

    from .io import write_mesh

    prog = _Progress(["reading model", "correcting", "writing outputs"], args.quiet)
    try:
        settings = _settings(args)
        _check(settings, correct=True)
        allowable = settings.allowable_stress_mpa()
        if Path(args.out).suffix.lower() not in (".obj", ".off", ".ply", ".stl"):
            raise ValueError(f"--out {args.out}: use an .obj, .off, .ply or .stl file name")
        model = _load(args)
        prog.next()
        positional, keyword = _engine_args(settings, model, correct=True)
        t = time.perf_counter()
        fix = osteon.correct(*positional, **keyword)
        secs = time.perf_counter() - t
        prog.next()
        write_mesh(args.out, fix.vertices, model.faces)
        rounds = len(fix.rounds)
        if args.json:
            rep = _report(args, model, settings, fix.before, secs, correction=fix)
            _write_json(args.json, rep)
        if args.png:
            _png(
                args,
                model,
                fix.after,
                allowable,
                before=fix.before,
                vertices=fix.vertices,
                title=f"{Path(args.model).name} corrected: F = {args.force:g} N, "
                f"[σ] = {allowable:g} MPa",
            )
        prog.next()
    finally:
        prog.close()
    if not args.quiet:
        status = "converged" if fix.converged else "NOT converged"
        print(
            f"{Path(args.model).name}: max stress {fix.before.max_stress:.2f} -> "
            f"{fix.after.max_stress:.2f} MPa ([σ] = {allowable:g} MPa); {rounds} rounds, "
            f"{status} in {1000 * secs:.1f} ms",
            file=out,
        )
        reason = fix.reason
        if reason and not fix.converged:
            print(f"why: {reason}", file=out)
        print(
            format_table(
                bone_table(fix.after, args.top, scales=fix.bone_scale), allowable, scales=True
            ),
            file=out,
        )
        print(f"corrected mesh written to {args.out}", file=out)
    return 0 if fix.converged else 1


def cmd_validate(args, out):

    stages = ["reading model", "analysing"] + (["meshing + solving (FEM)"] if args.fem else [])
    prog = _Progress(stages + ["writing outputs"], args.quiet)
    try:
        settings = _settings(args)
        _check(settings)
        allowable = settings.allowable_stress_mpa()
        model = _load(args)
        checks = model_checks(model)
        prog.next()
        a, secs = _analyze(settings, model)
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
            from . import fem

            if not checks["watertight"]:
                raise ValueError(f"{args.model}: the mesh is not closed; FEM needs a closed mesh")
            tools = fem.find_tools()
            missing = [k for k, v in tools.items() if v is None]
            if missing:
                raise ValueError(
                    "--fem needs the programs "
                    + " and ".join(missing)
                    + " (apt-get install gmsh calculix-ccx)"
                )
            secs_list = fem.pick_sections(a, model.heads, model.tails, n=args.sections)
            if not secs_list:
                raise ValueError(
                    "no section suitable for the FEM check (all near joints, the "
                    "held region or too stubby)"
                )
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
            )
            rep["fem"] = fem_rep.as_dict()
            for row in rep["fem"]["sections"] + rep["fem"]["failed_sections"]:
                row["bone_name"] = model.bone_names[row["bone"]] if row["bone"] >= 0 else None
            rep["fem"]["seconds"] = time.perf_counter() - t
            prog.next()
        if args.json:
            _write_json(args.json, rep)
        if args.png:
            marks = None if fem_rep is None else [s.center for s in fem_rep.sections]
            _png(
                args,
                model,
                a,
                allowable,
                marks=marks,
                title=f"{Path(args.model).name}: F = {args.force:g} N",
            )
            if fem_rep is not None:
                from .plots import save_fem_png

                p = Path(args.png)
                save_fem_png(p.with_name(p.stem + "_fem" + p.suffix), fem_rep)
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


def format_fem_table(rep, bone_names):
    head = f"{'#':>2} {'bone':<22} {'arm mm':>7} {'osteon MPa':>11} {'FEM MPa':>9} {'error':>7}"
    lines = [head, "-" * len(head)]
    for i, s in enumerate(rep.sections, 1):
        name = bone_names[s.bone] if 0 <= s.bone < len(bone_names) else str(s.bone)
        lines.append(
            f"{i:>2} {name[:22]:<22} {s.moment_arm_mm:>7.1f} {s.osteon_stress_mpa:>11.2f} "
            f"{s.fem_stress_mpa:>9.2f} {100 * s.rel_error:>+6.1f}%"
        )
    for f in rep.failed:
        name = bone_names[f["bone"]] if 0 <= f["bone"] < len(bone_names) else str(f["bone"])
        lines.append(f" - {name[:22]:<22} FEM meshing failed: {f['reason'][:60]}")
    lines.append(
        f"median |error| {100 * rep.median_error:.1f} %, worst {100 * rep.worst_error:.1f} %"
        f"; FEM {rep.nodes} nodes, {rep.elements} C3D10 tets, mesh "
        f"{rep.mesh_seconds:.1f} s + solve {rep.solve_seconds:.1f} s"
    )
    return "\n".join(lines)


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
        res["weight_rows_sum_to_1"] = bool(np.allclose(s[s > 0], 1.0))
    else:
        res["weights"] = "none (nearest bone)"
    return res


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    handler = {"analyze": cmd_analyze, "correct": cmd_correct, "validate": cmd_validate,
               "skeleton": cmd_skeleton}
    try:
        return handler[args.command](args, sys.stdout)
    except (ValueError, FileNotFoundError, RuntimeError) as e:
        msg = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        print(f"osteon: error: {msg}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("osteon: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
