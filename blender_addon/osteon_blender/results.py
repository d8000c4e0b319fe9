"""The panel's result: one report (``osteon.report``, the wheel's schema) becomes the
properties of ``scene.osteon`` the sidebar draws -- the summary, the rows, the tooltips -- for
Analyze, Correct and Live alike, so that all of them speak of the same governing quantity:
stress / the allowable that applies at that section (across or along the layers), MPa.
"""

from __future__ import annotations

import numpy as np

from . import state


def show(scene, report: dict, entry: dict, source: str) -> None:
    """Fill ``scene.osteon``'s result properties from ``report`` and remember ``entry``
    (``{"report", "analysis", "inputs", ...}``) as the result the panel shows; ``source``:
    "analyze", "correct" or "live"."""
    s = scene.osteon
    s.weak_bones.clear()
    for row in report["weak_bones"]:
        item = s.weak_bones.add()
        item.name = row["bone"]
        item.max_stress_mpa = row["max_stress_mpa"]
        item.ratio = row["ratio"]
        item.stress_mpa = row.get("stress_mpa") or 0.0
        item.allowable_mpa = row.get("allowable_mpa") or 0.0
        item.limit = row.get("limit") or ""
        item.scale = row["scale"]
        item.weak = row["weak"]
        item.status = "weak" if row["weak"] else "ok"
    s.skipped_sections = int(report.get("skipped_sections") or 0)
    s.doubt = report.get("doubt") or ""
    s.verdict = report.get("verdict") or ""
    for row in report.get("not_analysed_bones") or []:
        item = s.weak_bones.add()
        item.name = row["bone"]
        item.status = "not analysed"
        item.reason = row.get("reason") or ""
    worst = report.get("worst") or {}
    s.worst_bone = worst.get("bone") or ""
    s.worst_stress_mpa = worst.get("stress_mpa") or 0.0
    s.worst_allowable_mpa = worst.get("allowable_mpa") or 0.0
    s.worst_ratio = worst.get("ratio") or 0.0
    s.worst_limit = worst.get("limit") or ""
    s.has_result = True
    s.result_source = source
    s.result_object = report.get("object") or ""
    s.result_armature = report.get("armature") or ""
    # no section gave a stress (all skipped): 0.0 here, the doubt lines say why
    s.max_stress_mpa = report["max_stress_mpa"] if report["max_stress_mpa"] is not None else 0.0
    s.allowable_mpa = report["allowable_stress_mpa"]
    s.sections = report["sections"]
    s.weak_sections = report["weak_sections"]
    s.converged = report["converged"]
    state.of(scene).shown = entry


def worst_line(bone: str, stress_mpa: float, allowable_mpa: float, ratio: float,
               limit: str = "") -> str:
    """The verdict's number in words, the same in the summary, the INFO message and Live:
    "Worst σ/[σ] 2.08: antenna, 31.2 / 15.0 MPa across layers" (ratio = stress / the
    allowable at that section; which allowable: across or along the layers)."""
    text = f"Worst σ/[σ] {ratio:.2f}: {bone}, {stress_mpa:.1f} / {allowable_mpa:.1f} MPa"
    return f"{text} {limit}" if limit else text


def report_worst_line(report: dict) -> str | None:
    w = report.get("worst")
    if not w:
        return None
    return worst_line(w["bone"], w["stress_mpa"], w["allowable_mpa"], w["ratio"],
                      w.get("limit") or "")


def not_analysed_vertices(analysis, report: dict, bone_names) -> np.ndarray | None:
    """(V,) bool: vertices whose bone is "not analysed" (drawn magenta), or None."""
    bad = {r["bone"] for r in report.get("not_analysed_bones") or []}
    vb = getattr(analysis, "vertex_bone", None)
    if not bad or vb is None:
        return None
    idx = np.array([i for i, n in enumerate(bone_names) if n in bad], dtype=np.int64)
    return np.isin(np.asarray(vb, dtype=np.int64), idx)
