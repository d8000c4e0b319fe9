"""No import circles in the wheel's package nor in the Blender add-on (issue 34): read from the source, imports inside
functions included. The checker itself is tested on a package made here with a known cycle."""

from __future__ import annotations

from pathlib import Path

from import_graph import cycles, import_graph

ROOT = Path(__file__).resolve().parents[2]


def _write(base: Path, files: dict[str, str]) -> Path:
    for rel, text in files.items():
        p = base / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text)
    return base


def test_the_checker_finds_a_cycle_hidden_in_a_function(tmp_path):
    pkg = _write(tmp_path / "pkg", {
        "__init__.py": "from .a import f\n",
        "a.py": "def f():\n    from .sub.b import g\n    return g\n",
        "sub/__init__.py": "",
        "sub/b.py": "def g():\n    from .. import a\n    return a\n",
        "c.py": "from . import a\n",
    })
    assert cycles(import_graph(pkg, "pkg")) == [["pkg.a", "pkg.sub.b"]]


def test_the_checker_accepts_a_tree(tmp_path):
    pkg = _write(tmp_path / "pkg", {
        "__init__.py": "from .a import f\nfrom .b import g\n",
        "a.py": "from .b import g\n\ndef f():\n    return g()\n",
        "b.py": "import os\n\ndef g():\n    return os.sep\n",
    })
    graph = import_graph(pkg, "pkg")
    assert graph["pkg.a"] == {"pkg.b"}
    assert cycles(graph) == []


def _report(found: list[list[str]]) -> str:
    return "import circles: " + "; ".join(" <-> ".join(c) for c in found)


def test_the_wheel_has_no_import_cycle():
    graph = import_graph(ROOT / "python" / "osteon", "osteon")
    assert len(graph) > 30, "the package's modules were not found"
    found = cycles(graph)
    assert not found, _report(found)


def test_the_addon_has_no_import_cycle():
    """Read statically: no bpy needed (the add-on's three circles of issue 34 were found by
    this check before they were taken apart)."""
    graph = import_graph(ROOT / "blender_addon" / "osteon_blender", "osteon_blender")
    assert len(graph) > 20, "the add-on's modules were not found"
    found = cycles(graph)
    assert not found, _report(found)
