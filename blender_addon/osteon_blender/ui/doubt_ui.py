"""The result summary the panel shows: the verdict first, then the worst ratio, then what the
result does not cover (skipped and doubtful sections, issue 13: no false all-clear)."""

from __future__ import annotations

from .. import results


def _plural(n: int, word: str) -> str:
    return f"{n} {word}{'' if n == 1 else 's'}"


def summary_lines(s) -> list[tuple[str, str]]:
    """(text, icon) lines of the result summary (also used by the tests and the screenshot
    check): the first is the verdict -- "N bones over the limit", "All within the limit" or
    "Not analysed: <why>" -- never the object's name."""
    if not s.has_result:
        return [("Not analysed yet", "INFO")]
    live = " (Live)" if s.result_source == "live" else ""
    rows = list(s.weak_bones)
    weak = sum(1 for r in rows if r.weak)
    uncut = [r for r in rows if r.status == "not analysed"]
    lines = []
    if weak:
        lines.append((f"{_plural(weak, 'bone')} over the limit{live}", "ERROR"))
    elif s.verdict == "not analysed":
        why = uncut[0].reason.split(": ", 1)[-1] if uncut and uncut[0].reason else (
            "no section could be cut")
        lines.append((f"Not analysed: {why}", "QUESTION"))
    else:
        lines.append((f"All within the limit{live}", "CHECKMARK"))
    if s.worst_bone and s.sections:
        lines.append((results.worst_line(s.worst_bone, s.worst_stress_mpa, s.worst_allowable_mpa,
                                         s.worst_ratio, s.worst_limit), "NONE"))
    lines.append((f"{s.weak_sections} of {_plural(s.sections, 'section')} over", "NONE"))
    if weak and uncut:
        lines.append((f"{_plural(len(uncut), 'bone')} not analysed", "QUESTION"))
    if s.doubt:
        lines.append((s.doubt, "ERROR"))
    elif s.skipped_sections:
        lines.append((f"{s.skipped_sections} of {s.sections} sections skipped", "ERROR"))
    return lines
