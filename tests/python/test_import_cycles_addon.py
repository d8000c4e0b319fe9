"""No import circles in the Blender add-on (issue 34): read statically with ``ast`` (no bpy).

Every import of a module of the package counts, also one inside a function (an import moved
into a function hides a circle from Python, not from the reader).  A module's imports of its
own parent packages are what Python does anyway and are not counted; ``from . import x``
counts as an import of the submodule ``x`` when there is one, else of the package itself.
"""

from __future__ import annotations

import ast
from pathlib import Path

ADDON = Path(__file__).resolve().parents[2] / "blender_addon" / "osteon_blender"
PACKAGE = "osteon_blender"


def module_files(root: Path, package: str) -> dict[str, Path]:
    """Dotted module name -> file, for every .py of the package (``pkg.sub`` for
    ``pkg/sub/__init__.py``)."""
    out = {}
    for path in sorted(root.rglob("*.py")):
        if "_vendor" in path.parts:
            continue
        parts = list(path.relative_to(root).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join([package, *parts])] = path
    return out


def _resolve(current: str, is_package: bool, level: int, module: str | None) -> str:
    base = current.split(".")
    if not is_package:
        base = base[:-1]
    if level > 1:
        base = base[: len(base) - (level - 1)]
    return ".".join(base + ([module] if module else []))


def import_graph(root: Path = ADDON, package: str = PACKAGE) -> dict[str, set[str]]:
    """Module -> the modules of the package it imports (anywhere in its body)."""
    files = module_files(root, package)
    graph: dict[str, set[str]] = {m: set() for m in files}
    for name, path in files.items():
        is_package = path.name == "__init__.py"
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level == 0:
                    target = node.module or ""
                else:
                    target = _resolve(name, is_package, node.level, node.module)
                for alias in node.names:
                    sub = f"{target}.{alias.name}"
                    targets.append(sub if sub in files else target)
            for t in targets:
                if t in files and t != name and not name.startswith(t + "."):
                    graph[name].add(t)
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan), sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(found)


def test_the_checker_finds_a_circle_hidden_in_a_function(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("from . import a\n")
    (pkg / "a.py").write_text("from .sub import b\n")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "sub" / "b.py").write_text("def f():\n    from .. import a\n")
    (pkg / "c.py").write_text("from .a import x\n")
    assert cycles(import_graph(pkg, "pkg")) == [["pkg.a", "pkg.sub.b"]]


def test_addon_has_no_import_cycles():
    graph = import_graph()
    assert len(graph) > 20, "the add-on's modules were not found"
    found = cycles(graph)
    assert not found, "import circles in the add-on: " + "; ".join(" <-> ".join(c) for c in found)
