"""The panel's lines for skipped and doubtful sections (issue 13: no false all-clear)."""

from .. import core


def summary_lines(s) -> list[tuple[str, str]]:
    """(text, icon) lines the panel shows under the result (also used by the tests)."""
    lines = []
    if s.doubt:
        lines.append((s.doubt, "ERROR"))
    if s.verdict == "not analysed":
        lines.append(("Not analysed: no verdict (magenta: " + core.DOUBT_LEGEND + ")",
                      "QUESTION"))
    elif s.verdict == "ok":
        lines.append(("No weak bones", "CHECKMARK"))
    return lines


def draw_doubt(box, s) -> None:
    if s.skipped_sections or s.doubt:
        box.label(text=f"{s.skipped_sections} of {s.sections} sections skipped", icon="ERROR")
    for text, icon in summary_lines(s):
        if icon != "CHECKMARK":
            box.label(text=text, icon=icon)
