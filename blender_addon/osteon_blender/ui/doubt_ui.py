"""The result summary the panel shows: the verdict first, then the worst ratio, then what the
result does not cover (skipped and doubtful sections, issue 13: no false all-clear)."""

from __future__ import annotations

from .. import state


def _plural(n: int, word: str) -> str:
    return f"{n} {word}{'' if n == 1 else 's'}"


def worst_ratio(s) -> float | None:
    """The worst stress / allowable of the last result (the report's, which counts the
    layers' weaker strength across them), or max stress / allowable stress (MPa / MPa)."""
    st = state.get(s.id_data)
    rep = st.last["report"] if st is not None and st.last else None
    r = rep.get("stress_ratio") if rep else None
    if r is not None:
        return float(r)
    return s.max_stress_mpa / s.allowable_mpa if s.allowable_mpa > 0 else None


def summary_lines(s) -> list[tuple[str, str]]:
    """(text, icon) lines of the result summary (also used by the tests and the screenshot
    check): the first is the verdict -- "N bones over the limit", "All within the limit" or
    "Not analysed: <why>" -- never the object's name."""
    if not s.has_result:
        return [("Not analysed yet", "INFO")]
    rows = list(s.weak_bones)
    weak = sum(1 for r in rows if r.weak)
    uncut = [r for r in rows if r.status == "not analysed"]
    lines = []
    if weak:
        lines.append((f"{_plural(weak, 'bone')} over the limit", "ERROR"))
    elif s.verdict == "not analysed":
        why = uncut[0].reason.split(": ", 1)[-1] if uncut and uncut[0].reason else (
            "no section could be cut")
        lines.append((f"Not analysed: {why}", "QUESTION"))
    else:
        lines.append(("All within the limit", "CHECKMARK"))
    ratio = worst_ratio(s)
    if ratio is not None and s.sections:
        lines.append((f"Worst σ/[σ] {ratio:.2f}, {s.max_stress_mpa:.1f} MPa", "NONE"))
    lines.append((f"{s.weak_sections} of {_plural(s.sections, 'section')} over", "NONE"))
    if weak and uncut:
        lines.append((f"{_plural(len(uncut), 'bone')} not analysed", "QUESTION"))
    if s.doubt:
        lines.append((s.doubt, "ERROR"))
    elif s.skipped_sections:
        lines.append((f"{s.skipped_sections} of {s.sections} sections skipped", "ERROR"))
    return lines
