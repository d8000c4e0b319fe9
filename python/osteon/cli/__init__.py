"""The ``osteon`` command: analyse, correct and validate rigged models from files.

One module per job: ``parser`` (options and help), ``common`` (settings, reading, engine,
report, table, picture), ``analyze``, ``correct``, ``reinforce``, ``validate``, ``skeleton``. ``osteon.cli:main`` is the
console entry point. Units everywhere: millimetres of the printed object, newtons, MPa.
"""

from __future__ import annotations

import sys

from .analyze import analyze_model, cmd_analyze
from .common import CliError, bone_table, format_table
from .correct import cmd_correct
from .parser import DEFAULT_SAFETY_FACTOR, EXAMPLES, MATERIALS, build_parser
from .reinforce import cmd_reinforce
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
    "cmd_reinforce",
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
               "skeleton": cmd_skeleton, "batch": cmd_batch, "reinforce": cmd_reinforce}
    try:
        return handler[args.command](args, sys.stdout)
    except (ValueError, FileNotFoundError, RuntimeError) as e:
        _error(_named(_first_line(e), e, args))
        return 2
    except OSError as e:  # a folder given as a file, a full disk, no permission
        where = f"{e.filename}: " if e.filename else ""
        _error(f"{where}{e.strerror or _first_line(e)}")
        return 2
    except ModuleNotFoundError as e:
        _error(f"this needs the Python package {e.name!r} (pip install {e.name})")
        return 2
    except MemoryError:
        _error("out of memory (a model read far too big? see --height-mm and --max-sections)")
        return 2
    except KeyboardInterrupt:
        print("osteon: interrupted", file=sys.stderr)
        return 130
    except Exception as e:  # noqa: BLE001 - one line, not a traceback; a bug to report
        _error(_named(f"internal error ({type(e).__name__}: {_first_line(e)}); please report "
                      "it with the model", e, args))
        return 3


def _named(msg: str, e: BaseException, args) -> str:
    """``msg`` naming the model file when a cryptic third-party message was put in plain
    words (those name no file)."""
    model = getattr(args, "model", None)
    raw = str(e).strip().splitlines()[0] if str(e).strip() else ""
    if model and raw and raw not in msg and str(model) not in msg:
        from ..io.model import printable

        return f"{printable(model)}: {msg}"
    return msg


def _first_line(e: BaseException) -> str:
    from ..io.loader import plain_words

    text = str(e).strip()
    return plain_words(text.splitlines()[0]) if text else type(e).__name__


def _error(msg: str) -> None:
    from ..io.model import printable

    print(f"osteon: error: {printable(msg)}", file=sys.stderr)
