"""``osteon batch INPUTS… --out DIR``: the command-line front end of :mod:`osteon.batch`."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

BATCH_EXAMPLES = """\
examples:
  osteon batch library/ --out report                   # all cores
  osteon batch 'scans/**/*.stl' figures/*.glb --out report --material PETG --force 10
  osteon batch library/ --out report --resume          # after an interruption
  osteon batch library/ --out report --profile prusaslicer   # as PrusaSlicer prints them
  osteon batch library/ --out report --dask local      # a local Dask cluster
  osteon batch library/ --out report --dask tcp://scheduler:8786
"""


def add_batch_parser(sub) -> argparse.ArgumentParser:
    """Add the ``batch`` subcommand to the ``osteon`` parser's subparsers."""
    from .. import materials
    from ..batch.settings import DEFAULT_MODEL_TIMEOUT_S
    from .options import (
        MATERIALS,
        add_junction_switch,
        add_max_sections,
        add_notch_options,
        add_print_options,
    )

    p = sub.add_parser(
        "batch",
        help="analyse a whole library of models on all cores or a Dask cluster",
        description="Analyse every model in files, folders (recursive) and globs; one JSON "
        "per model, results.jsonl, summary.csv and a summary.html contact sheet in --out. "
        "Units: mm, N, MPa.",
        epilog=BATCH_EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("inputs", nargs="+", metavar="INPUT", help="model file, folder or glob")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder")
    p.add_argument("--height-mm", type=float, default=120.0, metavar="MM",
                   help="printed size in mm of each model's largest side (default 120)")
    p.add_argument("--axis", choices=["longest", "x", "y", "z"], default="longest",
                   help="which extent --height-mm sets (default: longest)")
    p.add_argument("--force", type=float, default=20.0, metavar="N",
                   help="force in newtons on the worst point of each branch (default 20)")
    p.add_argument("--material", default=materials.DEFAULT_MATERIAL, metavar="NAME",
                   help="material preset: " + ", ".join(f"{k} {v:g} MPa" for k, v in
                                                         MATERIALS.items())
                   + f" (default {materials.DEFAULT_MATERIAL}; see osteon/materials.py)")
    p.add_argument("--strength-mpa", type=float, metavar="MPA",
                   help="material strength in MPa (overrides the preset)")
    p.add_argument("--safety-factor", type=float, default=materials.DEFAULT_SAFETY_FACTOR,
                   metavar="K", help="allowable stress = strength / K "
                   f"(default {materials.DEFAULT_SAFETY_FACTOR:g})")
    p.add_argument("--interval", type=float, default=2.0, metavar="MM",
                   help="distance in mm between sections along each bone (default 2)")
    p.add_argument("--root", metavar="BONE", help="bone (name or index) held at its head")
    p.add_argument("--build-direction", default="0,0,1", metavar="X,Y,Z",
                   help="build (layer stacking) direction in each model's frame (default +Z)")
    p.add_argument("--layer-ratio", type=float, metavar="R",
                   help="layer / in-plane strength (default: the material preset's)")
    add_junction_switch(p)
    add_print_options(p)
    add_max_sections(p)
    p.add_argument("--model-timeout", type=float, default=DEFAULT_MODEL_TIMEOUT_S, metavar="S",
                   help="seconds one model may take; over it the model fails with that reason "
                   "and its worker process is killed with what it started, the engine's C++ "
                   "included (--jobs 1: one worker process; --dask: a child process of the "
                   f"Dask worker) (default {DEFAULT_MODEL_TIMEOUT_S:g}; 0 = none, and --jobs 1 "
                   "then runs in this process)")
    add_notch_options(p)
    p.add_argument("--correct", action="store_true",
                   help="also thicken weak bones and write each corrected mesh")
    p.add_argument("--max-scale", type=float, default=3.0, metavar="S",
                   help="with --correct: largest cross-section scale per bone (default 3)")
    p.add_argument("--max-rounds", type=int, default=100, metavar="N",
                   help="with --correct: most scaling rounds (default 100)")
    p.add_argument("--scaling", choices=("thin", "uniform"), default=None,
                   help="with --correct: thin (default) or uniform scaling")
    p.add_argument("--slicer-project", choices=("prusaslicer", "bambu", "orca"), default=None,
                   help="also reinforce each model under --profile (more walls / infill where "
                   "weak) and write ID.3mf for this slicer (docs/correction.md)")
    p.add_argument("--allow-open", action="store_true",
                   help="analyse open meshes too (flagged) instead of failing them")
    p.add_argument("--no-png", action="store_true", help="no stress pictures (faster)")
    p.add_argument("--resume", action="store_true",
                   help="skip the models already in DIR/results.jsonl")
    p.add_argument("-j", "--jobs", type=int, default=None, metavar="N",
                   help="worker processes, started once (default: all cores; 1 = one "
                   "worker, or this process with --model-timeout 0)")
    p.add_argument("--dask", metavar="ADDRESS",
                   help="run the tasks on a Dask scheduler (tcp://host:8786) or 'local' "
                   "(a LocalCluster of --jobs processes)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar, no summary")
    return p


def settings_from_args(args):
    """The batch settings: the shared Settings built as ``analyze`` builds them, plus the
    batch's own options."""
    from ..batch.settings import BatchSettings
    from .common import check, max_sections_of, settings_from_args

    shared = settings_from_args(args)
    check(shared, correct=args.correct)  # errors name the option
    if not args.model_timeout >= 0:
        raise ValueError(f"--model-timeout must be >= 0 s (0 = none), got {args.model_timeout}")
    return BatchSettings(settings=shared, correct=args.correct, png=not args.no_png,
                         allow_open=args.allow_open, model_timeout_s=args.model_timeout,
                         max_sections=max_sections_of(args),
                         slicer_project=getattr(args, "slicer_project", None))


def cmd_batch(args, out=sys.stdout) -> int:
    from ..batch.runner import dask_client, run

    settings = settings_from_args(args)
    settings.check()
    if args.jobs is not None and args.jobs < 1:
        raise ValueError(f"--jobs must be >= 1, got {args.jobs}")
    client = dask_client(args.dask, args.jobs) if args.dask else None
    t = time.perf_counter()
    counts = {"ok": 0, "skipped": 0, "failed": 0}
    weak = 0
    try:
        for rec in run(args.inputs, settings, client=client, workers=args.jobs, out=args.out,
                       resume=args.resume, progress=not args.quiet):
            counts[rec["status"]] = counts.get(rec["status"], 0) + 1
            weak += (rec.get("stress_ratio") or 0) > 1
    finally:
        if client is not None:
            cluster = getattr(client, "cluster", None)
            client.close()
            if args.dask == "local" and cluster is not None:
                cluster.close()
    secs = time.perf_counter() - t
    n = sum(counts.values())
    if not args.quiet:
        print(
            f"{n} models in {secs:.1f} s ({n / secs if secs > 0 else 0:.1f}/s): {counts['ok']} "
            f"analysed ({weak} weak), {counts['skipped']} skipped, {counts['failed']} failed",
            file=out,
        )
        print(f"contact sheet: {Path(args.out) / 'summary.html'}", file=out)
    return 0
