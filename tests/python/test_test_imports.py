"""The tests import nothing from ``bench/`` or ``scripts/`` (issue 34: benchmarks and developer
scripts may change or leave the tree; a test's yardstick lives beside the tests, in
``tests/python``). Checked on the source (``ast``), so an import inside a function counts too."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
TESTS = ROOT / "tests" / "python"


def _outside_modules() -> set[str]:
    """Module names that only bench/ or scripts/ provide (not also a file of tests/python)."""
    own = {p.stem for p in TESTS.glob("*.py")}
    return {p.stem for d in ("bench", "scripts") for p in (ROOT / d).glob("*.py")} - own


def offending_imports(source: str, outside: set[str]) -> list[str]:
    """Each import of a module in ``outside`` and each ``sys.path`` edit naming bench/scripts."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found += [a.name for a in node.names if a.name.split(".")[0] in outside]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            if node.module.split(".")[0] in outside:
                found.append(node.module)
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
              and ast.unparse(node.func).startswith("sys.path.")):
            text = ast.unparse(node)
            if "'bench'" in text or "'scripts'" in text or "bench/" in text or "scripts/" in text:
                found.append(text)
    return found


def test_the_checker_finds_an_import_from_bench_inside_a_function():
    source = (
        "import numpy\n"
        "def f():\n"
        "    import sys\n"
        "    sys.path.insert(0, str(ROOT / 'bench'))\n"
        "    from compare_builds import child_arrays\n"
        "    import study_notch\n")
    found = offending_imports(source, {"compare_builds", "study_notch"})
    assert len(found) == 3, found
    assert offending_imports("import numpy\nfrom shapes import capsule\n", {"compare_builds"}) == []


def test_no_test_imports_from_bench_or_scripts():
    outside = _outside_modules()
    assert "compare_builds" in outside and "study_notch" in outside  # the scan sees both folders
    bad = {p.name: found for p in sorted(TESTS.glob("*.py"))
           if (found := offending_imports(p.read_text(encoding="utf-8"), outside))}
    assert not bad, f"tests import from bench/ or scripts/: {bad}"
