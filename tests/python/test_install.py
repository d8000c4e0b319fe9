"""The default install is complete: every third-party module the package imports is a regular
dependency, and the ``osteon`` console script runs on a real model in a fresh process."""

from __future__ import annotations

import ast
import importlib.metadata
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import DATA

PACKAGE = Path(__file__).resolve().parents[2] / "python" / "osteon"
# import name -> distribution name where they differ
DIST_OF = {"sklearn": "scikit-learn", "yaml": "pyyaml", "PIL": "pillow"}


def _third_party_imports() -> set[str]:
    names = set()
    for path in PACKAGE.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                names.update(a.name.split(".")[0] for a in node.names)
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names.add(node.module.split(".")[0])
    return {n for n in names if n not in sys.stdlib_module_names and n not in ("osteon", "_osteon")}


def _requirement_names(reqs) -> set[str]:
    out = set()
    for r in reqs or []:
        if "extra ==" in r:
            continue  # an optional extra, not the default install
        out.add(re.split(r"[\s<>=!~;\[(]", r, maxsplit=1)[0].lower().replace("_", "-"))
    return out


def test_every_imported_module_is_a_regular_dependency():
    imported = _third_party_imports()
    assert {"numpy", "scipy", "trimesh", "matplotlib", "tqdm"} <= imported
    required = _requirement_names(importlib.metadata.requires("osteon"))
    missing = {DIST_OF.get(n, n).lower() for n in imported} - required
    assert not missing, f"imported by python/osteon but not a regular dependency: {missing}"


def _console_script() -> str:
    exe = Path(sys.executable).with_name("osteon")
    if exe.is_file():
        return str(exe)
    found = shutil.which("osteon")
    if not found:
        pytest.fail("no 'osteon' console script next to the interpreter or on PATH")
    return found


def test_console_script_analyzes_a_model(tmp_path):
    """`osteon analyze` as a user types it: a fresh process, the installed entry point."""
    model = DATA / "libigl-tutorial-data" / "arm.obj"
    js, png = tmp_path / "r.json", tmp_path / "r.png"
    env = dict(os.environ, MPLBACKEND="Agg")
    res = subprocess.run([_console_script(), "analyze", str(model), "--height-mm", "120",
                          "--force", "20", "--material", "PLA", "--json", str(js),
                          "--png", str(png)],
                         capture_output=True, text=True, env=env, timeout=300, check=False)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "Traceback" not in res.stderr
    rep = json.loads(js.read_text())
    assert rep["max_stress_mpa"] > 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
