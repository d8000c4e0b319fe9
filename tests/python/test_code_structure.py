"""The engine's code stays readable: no function in cpp/src longer than 120 lines.

A small brace-matching scanner (no compiler needed): comments, string and character literals and
preprocessor lines are blanked out, then every ``{`` outside a function body is classified by
the text before it (since the last ``;``, ``{`` or ``}``): a namespace, class, struct, union or
enum opens a scope whose members are scanned in turn; a text ending in a parameter list (after
qualifiers such as ``const``, ``noexcept``, ``override`` or a trailing return type), or a
constructor's initialiser list, opens a function body, which is skipped to its matching ``}``
(lambdas inside count toward the function); anything else (a brace initialiser) is skipped. A
function's length runs from the line of its name to the line of its closing brace.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[2] / "cpp" / "src"
MAX_FUNCTION_LINES = 120

# One qualifier at the end of a signature (after its parameter list); stripped one at a time.
_QUALIFIER = re.compile(
    r"(\bconst|\bnoexcept(\s*\([^()]*\))?|\boverride|\bfinal|\bmutable|\bvolatile|&&?|"
    r"->[^(){};]*)$")
_CTOR_INIT = re.compile(r"\)\s*(const\s*|noexcept\s*)*:(?!:)")
_SCOPE = re.compile(r"\b(namespace|class|struct|union|enum)\b")


_NOT_CODE = re.compile(
    r"//[^\n]*"                      # line comment
    r"|/\*.*?\*/"                    # block comment
    r'|"(?:\\.|[^"\\\n])*"'           # string literal
    r"|'(?:\\.|[^'\\\n])*'"           # character literal
    r"|^[ \t]*#(?:\\\n|[^\n])*",     # preprocessor line, with its continuations
    re.DOTALL | re.MULTILINE)


def _blank(text: str) -> str:
    """text with comments, string/char literals and preprocessor lines replaced by spaces (line
    breaks kept, so offsets and line numbers stay)."""
    return _NOT_CODE.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)), text)


def _matching(text: str, i: int, open_: str, close: str) -> int:
    """Index of the bracket closing the one at i."""
    depth = 0
    for j in range(i, len(text)):
        if text[j] == open_:
            depth += 1
        elif text[j] == close:
            depth -= 1
            if depth == 0:
                return j
    raise ValueError(f"unbalanced {open_} at offset {i}")


def _function_name(header: str) -> tuple[str, int] | None:
    """(name, offset of the name in header) when header ends a function's signature, else None."""
    init = _CTOR_INIT.search(header)
    if init and header[:init.start()].count("(") == header[:init.start() + 1].count(")"):
        header = header[:init.start() + 1]  # the parameters' closing parenthesis
    elif init:
        return None
    header = header.rstrip()
    while m := _QUALIFIER.search(header):
        header = header[:m.start()].rstrip()
    if not header.endswith(")"):
        return None
    depth = 0
    for j in range(len(header) - 1, -1, -1):
        depth += {")": 1, "(": -1}.get(header[j], 0)
        if depth == 0:
            break
    before = header[:j].rstrip()
    if before.endswith("]"):
        return "<lambda>", len(before) - 1
    m = re.search(r"(operator\s*[^\s\w]+|operator\s+\w[\w:<>]*|[~\w:]+)$", before)
    if not m or m.group(1) in {"if", "for", "while", "switch", "catch", "return"}:
        return None
    return m.group(1).strip(), m.start(1)


def scan_functions(text: str) -> list[tuple[str, int, int]]:
    """(name, first line, length in lines) of every function defined in C++ source text."""
    code = _blank(text)
    found = []
    header_start = 0
    i = 0
    while i < len(code):
        c = code[i]
        if c in ";}":
            header_start = i + 1
        elif c == "{":
            header = code[header_start:i]
            if _CTOR_INIT.search(header) and re.search(r"[\w>]\s*$", header):
                i = _matching(code, i, "{", "}") + 1  # a member's brace initialiser
                continue
            named = _function_name(header.rstrip())
            if named is not None:
                end = _matching(code, i, "{", "}")
                first = code.count("\n", 0, header_start + named[1]) + 1
                last = code.count("\n", 0, end) + 1
                found.append((named[0], first, last - first + 1))
                i = end + 1
                header_start = i
                continue
            if not _SCOPE.search(header):  # a brace initialiser: nothing to scan inside
                i = _matching(code, i, "{", "}") + 1
                continue
            header_start = i + 1  # a namespace or class: scan its members
        i += 1
    return found


def _sources() -> list[Path]:
    return sorted(p for p in SRC.iterdir() if p.suffix in (".cpp", ".hpp"))


def test_scanner_counts_functions_of_a_synthetic_snippet():
    long_body = "\n".join(f"  x += {k};  // }} {{ not braces" for k in range(126))
    snippet = f"""#include <vector>
#define BRACES {{ }}
namespace demo {{
/* a comment with a brace {{ */
struct Point {{
  double x{{0.0}}, y = 1.0;
  explicit Point(double a) : x{{a}}, y(2.0 * a) {{
    if (a > 0) {{ y = a; }}
  }}
  double norm() const noexcept {{ return x * x + y * y; }}
}};
const std::vector<int> kTable = {{1, 2, 3}};
int long_one(int x)
{{
{long_body}
  return x;
}}
auto trailing(int a) -> std::vector<int> {{
  auto f = [&](int b) {{
    return std::vector<int>{{a, b, '}}'}};
  }};
  const char* s = "{{{{";
  return f(a);
}}
}}  // namespace demo
"""
    found = scan_functions(snippet)
    assert [(name, length) for name, _, length in found] == [
        ("Point", 3), ("norm", 1), ("long_one", 130), ("trailing", 7)]
    assert [first for _, first, _ in found] == [7, 10, 13, 143]


def test_scanner_finds_the_engines_functions():
    # A scanner that silently found nothing would pass the length test below.
    names = {name for p in _sources() for name, _, _ in scan_functions(p.read_text())}
    assert {"material_regions", "select_region", "region_thickness", "loose_pieces",
            "assemble_loops", "parallel_for"} <= {n.split("::")[-1] for n in names}
    assert len(names) > 150


@pytest.mark.parametrize("limit", [MAX_FUNCTION_LINES])
def test_no_engine_function_longer_than_the_limit(limit):
    too_long = [f"{p.name}:{name} (line {first}): {length} lines"
                for p in _sources() for name, first, length in scan_functions(p.read_text())
                if length > limit]
    sizes = ", ".join(f"{p.name} {len(p.read_text().splitlines())}"
                      for p in sorted(_sources(), key=lambda p: -len(p.read_text().splitlines())))
    assert not too_long, (f"functions over {limit} lines in cpp/src (split them into named steps):"
                          "\n  " + "\n  ".join(too_long) + f"\nfile lengths (lines): {sizes}")
