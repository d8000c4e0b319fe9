"""The ``osteon`` command: analyse, correct and validate rigged models from files.

One module per job: ``parser`` (options and help), ``common`` (settings, reading, engine,
report, table, picture), ``analyze``, ``correct``, ``validate``, ``skeleton``. ``osteon.cli:main`` is the
console entry point. Units everywhere: millimetres of the printed object, newtons, MPa.
"""

from __future__ import annotations

import sys

from .analyze import analyze_model, cmd_analyze
from .common import CliError, bone_table, format_table
from .correct import cmd_correct
from .parser import DEFAULT_SAFETY_FACTOR, EXAMPLES, MATERIALS, build_parser
from .skeleton import cmd_skeleton
from .validate import cmd_validate, format_fem_table, model_checks

__all__ = [
    "DEFAULT_SAFETY_FACTOR",
    "EXAMPLES",
    "MATERIALS",
    "CliError",
    "analyze_model",
    "bone_table",
    "build_parser",
    "cmd_analyze",
    "cmd_correct",
    "cmd_skeleton",
    "cmd_validate",
    "format_fem_table",
    "format_table",
    "main",
    "model_checks",
]


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    from .batch import cmd_batch

    handler = {"analyze": cmd_analyze, "correct": cmd_correct, "validate": cmd_validate,
               "skeleton": cmd_skeleton, "batch": cmd_batch}
    try:
        return handler[args.command](args, sys.stdout)
    except (ValueError, FileNotFoundError, RuntimeError) as e:
        msg = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        print(f"osteon: error: {msg}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("osteon: interrupted", file=sys.stderr)
        return 130
