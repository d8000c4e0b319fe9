"""No import circles in the wheel's package (issue 34): read from the source, imports inside
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


def test_the_wheel_has_no_import_cycle():
    graph = import_graph(ROOT / "python" / "osteon", "osteon")
    assert len(graph) > 30  # the whole package was read
    assert cycles(graph) == []
