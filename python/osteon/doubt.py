"""Sections the engine skipped or doubts, counted per bone: no false all-clear (issue 13).

Written over the flag bits the engine exposes (``osteon.SECTION_FLAGS``, name -> bit), so
flags added later (``unreliable``, ``too_thin``) plug in by name.

* **skipped**: the section has no usable stress (non-finite stress, or a flag in
  :data:`SKIP_FLAGS` set): it says nothing about the part it cuts.
* **doubtful**: the section has a stress but its cut is suspect (a flag in
  :data:`DOUBT_FLAGS`: open mesh, bone outside the mesh, non-manifold edges).
* a bone with more than :data:`NOT_ANALYSED_SHARE` of its sections skipped is
  **not analysed**: it is never reported as safe.
"""

from __future__ import annotations

import numpy as np

#: flags that mean the section gave no stress
SKIP_FLAGS = ("empty", "degenerate", "unreliable", "too_thin")
#: flags that mean the section's stress rests on a suspect cut
DOUBT_FLAGS = ("open", "outside", "non_manifold")
#: a bone with more than this share of its sections skipped is "not analysed"
NOT_ANALYSED_SHARE = 0.25

#: plain-language reason of each flag (unknown flags are shown by their name)
REASONS = {
    "open": "the mesh is open there",
    "empty": "nothing was cut there",
    "degenerate": "the cut has no area there",
    # issue 36: RigNet 9000's root_dup_0 read 268 MPa at a 2.0 mm interval and "unreliable" at
    # 2.001 mm: with the bone point in no material, the engine takes the piece of the plane
    # holding most of the bone's own skin cut, and two pieces nearly tied there (a 26 mm-far
    # 25.6 mm² piece, or a sliver under 10 % of the median area: unreliable)
    "outside": "the bone lies outside the mesh there (the section is the piece of the plane "
               "holding most of the bone's own skin; a small shift of the plane can pick "
               "another piece)",
    "non_manifold": "the mesh is non-manifold there",
    "unreliable": "the cut is unreliable there",
    "too_thin": "the part is thinner than printable there",
    "hollow": "the bone lies in a hole there",
    "gap_closed": "gaps in the cut were closed there",
    "junction": "a side branch is cut there: only the core that continues counts",
    "notch": "a corner is there: its stress peak counts (docs/notch.md)",
}


def flag_table() -> dict[str, int]:
    """Name -> bit of every section flag the engine exposes."""
    try:
        import osteon

        return dict(osteon.SECTION_FLAGS)
    except (ImportError, AttributeError):  # pragma: no cover - engine without the table
        return {}


def _mask(flags: np.ndarray, names, table) -> np.ndarray:
    bits = 0
    for n in names:
        bits |= int(table.get(n, 0))
    return (flags & bits) != 0


#: what a user can do about each flag's sections (front-end neutral words)
FIXES = {
    "open": "close the mesh's holes there",
    "empty": "check that the bone runs through the mesh",
    "outside": "move the bone inside the mesh or shorten it",
    "non_manifold": "make the mesh manifold there",
    "degenerate": "check that the bone runs through the mesh",
    "hollow": "move the bone into the solid part",
}


def fix(names) -> str:
    """What to do about the most telling of the flags ``names`` ("" when nothing helps)."""
    order = ["open", "outside", "non_manifold", "hollow", "degenerate", "empty"]
    for n in sorted(set(names), key=lambda n: order.index(n) if n in order else len(order)):
        if n in FIXES:
            return FIXES[n]
    return ""


def reason(names) -> str:
    """One sentence part from flag names, most telling first (``open`` before ``empty``)."""
    order = ["open", "outside", "non_manifold", "too_thin", "unreliable", "degenerate", "empty",
             "hollow", "gap_closed", "junction", "notch"]
    names = sorted(set(names), key=lambda n: order.index(n) if n in order else len(order))
    return "; ".join(REASONS.get(n, n.replace("_", " ")) for n in names[:2])


def section_doubt(analysis) -> dict:
    """Per-section masks and counts of an ``osteon.Analysis`` (or anything with ``stress``,
    ``section_bone`` and optionally ``section_flags``).

    Returns ``skipped`` (S,) bool, ``doubtful`` (S,) bool (not skipped, suspect cut),
    ``by_flag`` {flag name: sections with it}, ``skipped_by_flag``, ``flag_names`` (S,) list of
    lists of names."""
    stress = np.asarray(analysis.stress, dtype=np.float64)
    n = len(stress)
    flags = getattr(analysis, "section_flags", None)
    flags = np.zeros(n, np.int64) if flags is None else np.asarray(flags, dtype=np.int64)
    table = flag_table()
    skipped = ~np.isfinite(stress) | _mask(flags, SKIP_FLAGS, table)
    doubtful = ~skipped & _mask(flags, DOUBT_FLAGS, table)
    # every flag at once: (S, K) section has flag k
    has = (flags[:, None] & np.array(list(table.values()), dtype=np.int64)) != 0
    by_flag = dict(zip(table, has.sum(axis=0).tolist()))
    skipped_by_flag = dict(zip(table, has[skipped].sum(axis=0).tolist()))
    # Python ints (a NumPy scalar's & costs ~10x more); most sections have no flag
    bits = list(table.items())
    names = [[k for k, b in bits if f & b] if f else [] for f in flags.tolist()]
    return {"skipped": skipped, "doubtful": doubtful, "flags": flags,
            "by_flag": {k: v for k, v in by_flag.items() if v},
            "skipped_by_flag": {k: v for k, v in skipped_by_flag.items() if v},
            "flag_names": names}


def bone_doubt(analysis, n_bones: int, share: float = NOT_ANALYSED_SHARE,
               d: dict | None = None) -> list[dict]:
    """Per bone: ``sections``, ``skipped_sections``, ``doubtful_sections``, ``not_analysed``
    (more than ``share`` of its sections skipped, or it has sections and none gave a stress;
    never a bone that deforms no vertex, e.g. a glTF ``_rootJoint``: there is nothing of the
    model to analyse along it) and ``reason`` ("12 of 61 sections could not be cut: the mesh is
    open there"). ``d``: the analysis's :func:`section_doubt`, when the caller has it."""
    d = section_doubt(analysis) if d is None else d
    sb = np.asarray(analysis.section_bone, dtype=np.int64)
    count = np.bincount(sb, minlength=n_bones)
    nskip = np.bincount(sb, weights=d["skipped"], minlength=n_bones).astype(int)
    ndoubt = np.bincount(sb, weights=d["doubtful"], minlength=n_bones).astype(int)
    vb = getattr(analysis, "vertex_bone", None)
    # which bones deform a vertex: read only for bones with skipped sections (a pass over
    # every vertex, which most results do not need)
    owns = (np.bincount(np.asarray(vb, dtype=np.int64)[np.asarray(vb) >= 0], minlength=n_bones)
            > 0 if vb is not None and nskip.any() else np.ones(n_bones, bool))
    # the skipped or doubtful sections of each bone, in section order (one pass)
    suspect: list[list[int]] = [[] for _ in range(n_bones)]
    for i in np.flatnonzero(d["skipped"] | d["doubtful"]).tolist():
        if 0 <= sb[i] < n_bones:
            suspect[int(sb[i])].append(i)
    out = []
    for b in range(n_bones):
        sel = suspect[b]
        names = [n for i in sel for n in d["flag_names"][i]]
        if len(sel) and not names:
            names = ["empty"]
        na = bool(count[b] > 0 and owns[b]
                  and (nskip[b] > share * count[b] or nskip[b] == count[b]))
        text = ""
        if nskip[b]:
            text = f"{nskip[b]} of {count[b]} sections could not be cut: {reason(names)}"
            if not owns[b]:
                text += " (the bone deforms no vertex: nothing to analyse)"
        elif ndoubt[b]:
            text = f"{ndoubt[b]} of {count[b]} sections are doubtful: {reason(names)}"
        out.append({"sections": int(count[b]), "skipped_sections": int(nskip[b]),
                    "doubtful_sections": int(ndoubt[b]), "not_analysed": na, "reason": text})
    return out


def worst_section_doubt(analysis, d: dict | None = None) -> list[str]:
    """Flag names of the section that gives the maximum stress ([] if it is a plain result);
    as the engine's maximum, among the sections not too thin to print. ``d``: the analysis's
    :func:`section_doubt`, when the caller has it."""
    stress = np.asarray(analysis.stress, dtype=np.float64)
    ok = np.isfinite(stress)
    flags = getattr(analysis, "section_flags", None)
    if flags is not None:
        ok &= ~_mask(np.asarray(flags, dtype=np.int64), ("too_thin",), flag_table())
    if not ok.any():
        return []
    i = int(np.flatnonzero(ok)[np.argmax(stress[ok])])
    d = section_doubt(analysis) if d is None else d
    if not (d["doubtful"][i] or d["skipped"][i]):
        return []
    return [n for n in d["flag_names"][i] if n in DOUBT_FLAGS or n in SKIP_FLAGS]


def summary_text(report: dict) -> str:
    """The doubt part of a summary line ("" when every section was cut cleanly)."""
    s = report.get("skipped_sections") or 0
    parts = []
    if s:
        flags = report.get("skipped_by_flag") or {"empty": 1}
        text = f"{s} of {report['sections']} sections could not be cut: {reason(flags)}"
        # which bones, and what to do: a user can act on a name, not on a count
        where = sorted(((r["skipped_sections"], r["bone"]) for r in report.get("bones") or []
                        if r.get("skipped_sections")), key=lambda t: -t[0])
        if where:
            text += " (" + ", ".join(f"{b} {n}" for n, b in where[:4])
            text += ", ..." if len(where) > 4 else ""
            text += ")"
        todo = fix(flags)
        parts.append(text + (f": {todo}" if todo else ""))
    na = report.get("not_analysed_bones") or []
    if na:
        parts.append(f"{len(na)} bone{'s' if len(na) != 1 else ''} not analysed ("
                     + ", ".join(r["bone"] for r in na[:5]) + ")")
    doubt = report.get("max_stress_doubt") or []
    if doubt:
        parts.append(f"the max stress rests on a doubtful section ({reason(doubt)})")
    return "; ".join(parts)


def analysis_text(analysis, bone_names) -> str:
    """:func:`summary_text` straight from an analysis (for the CLI's summary line)."""
    d = section_doubt(analysis)
    per_bone = bone_doubt(analysis, len(bone_names))
    sb = np.asarray(analysis.section_bone, dtype=np.int64)
    nskip = np.bincount(sb[d["skipped"]], minlength=len(bone_names))
    return summary_text({
        "sections": len(d["skipped"]),
        "bones": [{"bone": bone_names[b], "skipped_sections": int(nskip[b])}
                  for b in range(len(bone_names)) if nskip[b]],
        "skipped_sections": int(np.count_nonzero(d["skipped"])),
        "skipped_by_flag": d["skipped_by_flag"],
        "not_analysed_bones": [{"bone": bone_names[b]} for b, r in enumerate(per_bone)
                               if r["not_analysed"]],
        "max_stress_doubt": worst_section_doubt(analysis),
    })
