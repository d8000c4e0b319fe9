"""The one analysis report: allowable stress, the per-bone table and the JSON schema.

Used by the CLI (``osteon analyze/correct``), the Blender add-on (operators, batch script) and
batch runs, so that the same model and settings give the same JSON everywhere.

Rules: units in every key (mm, N, MPa); a non-finite number becomes ``null`` (JSON has no NaN);
every key of the schema is present in every report (``null`` where it does not apply);
``schema_version`` changes when a key is renamed or removed.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from . import doubt

#: bump when a key is renamed, removed or changes meaning (adding keys keeps the version).
#: 2 (issue 31): ``modulus_mm3`` / ``area_mm2`` of a section are the printed section's under a
#: print profile (``print_profile``; solid: as before), ``solid_modulus_mm3`` the cut's.
SCHEMA_VERSION = 2
UNITS = {"length": "mm", "force": "N", "stress": "MPa"}


def allowable_stress(strength_mpa: float, safety_factor: float) -> float:
    """Allowable stress [σ] in MPa = material strength (MPa) / safety factor."""
    if not (float(strength_mpa) > 0.0 and math.isfinite(strength_mpa)):
        raise ValueError(f"material strength must be a positive number of MPa, got {strength_mpa}")
    if not (float(safety_factor) > 0.0 and math.isfinite(safety_factor)):
        raise ValueError(f"safety factor must be a positive number, got {safety_factor}")
    return float(strength_mpa) / float(safety_factor)


def finite(x) -> float | None:
    """The one rule for numbers in a report: a finite float, or ``None`` (JSON null)."""
    if x is None:
        return None
    x = float(x)
    return x if math.isfinite(x) else None


def bone_table(section_bone, stress, weak, bone_names, allowable_mpa: float,
               bone_scale=None, stress_ratio=None, across_layers=None,
               section_allowable=None, stress_concentration=None) -> list[dict]:
    """One row per bone that has sections, highest stress ratio first (bones whose sections
    have no finite stress last, with ``null`` stress).

    ``section_bone`` (S,) int, ``stress`` (S,) MPa, ``weak`` (S,) bool, ``bone_names`` (B,),
    ``bone_scale`` (B,) or None; ``stress_ratio`` (S,) stress / the section's allowable
    (FDM layers, docs/printing.md; None: stress / ``allowable_mpa``), ``across_layers`` (S,)
    bool or None. Row: ``bone``, ``index``, ``max_stress_mpa``, ``ratio`` (the bone's largest
    stress ratio), ``limit`` ("across layers" / "along layers" at that section), ``weak`` (a
    weak section), ``weak_sections``, ``sections``, ``scale`` (the correction's cross-section
    scale, 1 = unchanged); ``stress_mpa`` and ``allowable_mpa``: the stress and the allowable
    (``section_allowable`` (S,) MPa, else ``allowable_mpa``) of the section that governs, so
    that ``ratio == stress_mpa / allowable_mpa`` (``max_stress_mpa`` may lie elsewhere on the
    bone, where the allowable is higher)."""
    section_bone = np.asarray(section_bone, dtype=np.int64)
    stress = np.asarray(stress, dtype=np.float64)
    weak = np.asarray(weak, dtype=bool)
    nb = len(bone_names)
    count = np.bincount(section_bone, minlength=nb)
    nweak = np.bincount(section_bone, weights=weak, minlength=nb)
    ok = np.isfinite(stress)
    mx = np.full(nb, -np.inf)
    np.maximum.at(mx, section_bone[ok], stress[ok])
    ratio_s = (stress / float(allowable_mpa) if stress_ratio is None
               else np.asarray(stress_ratio, dtype=np.float64))
    across = (np.zeros(len(stress), bool) if across_layers is None
              else np.asarray(across_layers, dtype=bool))
    rmax = np.full(nb, -np.inf)
    where = np.full(nb, -1)
    idx = np.flatnonzero(ok & np.isfinite(ratio_s))
    # per bone its worst section: the last of that bone in ascending (stable) ratio order,
    # i.e. the first in the reversed order
    last_first = idx[np.argsort(ratio_s[idx], kind="stable")][::-1]
    bones, first = np.unique(section_bone[last_first], return_index=True)
    where[bones] = last_first[first]
    rmax[bones] = ratio_s[where[bones]]
    allow_s = (np.full(len(stress), float(allowable_mpa)) if section_allowable is None
               else np.asarray(section_allowable, dtype=np.float64))
    have = np.flatnonzero(count > 0)
    key = np.where(np.isfinite(rmax[have]), -rmax[have], np.inf)
    rows = []
    for b in have[np.argsort(key, kind="stable")]:
        m = finite(mx[b])
        rows.append({
            "bone": bone_names[b],
            "index": int(b),
            "max_stress_mpa": m,
            "ratio": None if m is None else finite(rmax[b]),
            "stress_mpa": None if where[b] < 0 else finite(stress[where[b]]),
            "allowable_mpa": None if where[b] < 0 else finite(allow_s[where[b]]),
            "limit": None if where[b] < 0 else
            ("across layers" if across[where[b]] else "along layers"),
            "weak": bool(nweak[b] > 0),
            "weak_sections": int(nweak[b]),
            "sections": int(count[b]),
            "scale": 1.0 if bone_scale is None else float(bone_scale[b]),
            "stress_concentration": None if stress_concentration is None or where[b] < 0
            else finite(stress_concentration[where[b]]),
        })
    return rows


def worst_of(rows: list[dict]) -> dict | None:
    """The governing section of a bone table (:func:`bone_table`, worst first): ``bone``,
    ``stress_mpa``, ``allowable_mpa``, ``ratio``, ``limit``; None without a finite stress."""
    for r in rows:
        if r.get("ratio") is not None and r.get("stress_mpa") is not None:
            return {k: r[k] for k in ("bone", "stress_mpa", "allowable_mpa", "ratio", "limit")}
    return None


def too_thin_mask(a) -> np.ndarray:
    """(S,) bool: the sections of analysis ``a`` too thin to print (flag ``too_thin``). The
    engine leaves them out of the max stress and the weak count; the bone rows (JSON report,
    CLI table) leave them out too, so that no row contradicts the headline (issue 36), and the
    report lists them apart (``too_thin_sections``)."""
    flags = getattr(a, "section_flags", None)
    if flags is None:
        return np.zeros(len(a.stress), dtype=bool)
    from . import SECTION_FLAGS

    return (np.asarray(flags) & SECTION_FLAGS["too_thin"]) != 0


def printable_stress(a) -> np.ndarray:
    """(S,) MPa: the section stresses of ``a`` with the too-thin sections (:func:`too_thin_mask`)
    as NaN, what the bone rows are made of."""
    return np.where(too_thin_mask(a), np.nan, np.asarray(a.stress, dtype=np.float64))


def _analysis_table(a, bone_names, allowable_mpa, bone_scale=None, section_doubt=None):
    rows = bone_table(a.section_bone, printable_stress(a), a.weak, bone_names, allowable_mpa,
                      bone_scale,
                      getattr(a, "stress_ratio", None), getattr(a, "across_layers", None),
                      getattr(a, "section_allowable", None),
                      getattr(a, "stress_concentration", None))
    # skipped / doubtful sections per bone (osteon.doubt): a bone with too many skipped
    # sections is "not analysed", never "ok"
    per_bone = doubt.bone_doubt(a, len(bone_names), d=section_doubt)
    for r in rows:
        d = per_bone[r["index"]]
        r["skipped_sections"] = d["skipped_sections"]
        r["doubtful_sections"] = d["doubtful_sections"]
        r["status"] = ("not analysed" if d["not_analysed"] else "weak" if r["weak"] else "ok")
        r["reason"] = d["reason"] or None
    return rows


def _finite_list(x) -> list:
    """``finite`` over a whole (S,) or (S, k) array, as (nested) lists: one ``tolist``, then
    ``None`` only where a value is not finite (the per-section loop stays light)."""
    a = np.asarray(x, dtype=np.float64)
    out = a.tolist()
    for idx in np.argwhere(~np.isfinite(a)):
        if a.ndim == 1:
            out[idx[0]] = None
        else:
            out[idx[0]][idx[1]] = None
    return out


#: report key -> ``Analysis`` field of the printed section (issue 31, docs/printing.md)
PRINTED_SECTION_FIELDS = {"solid_modulus_mm3": "section_solid_modulus",
                          "wall_area_mm2": "section_wall_area",
                          "skin_area_mm2": "section_skin_area",
                          "infill_area_mm2": "section_infill_area"}


def section_rows(a, bone_names) -> list[dict]:
    """Every section of an ``osteon.Analysis``: bone, position (mm), area (mm²), modulus
    (mm³), moment arm (mm), moment (N·mm), stress (MPa), culled, weak. Under a print profile
    (docs/printing.md) ``modulus_mm3`` is the printed section's (what the stress uses),
    ``solid_modulus_mm3`` the solid cut's, and ``wall_area_mm2`` / ``skin_area_mm2`` /
    ``infill_area_mm2`` the printed section's perimeters, solid skins and sparse-infill region
    (``null`` where the engine gives none; solid: ``solid_modulus_mm3`` = ``modulus_mm3``). At a ``junction``
    section area and modulus are the core's (the material that continues through the plane,
    docs/junctions.md) and ``cut_area_mm2`` / ``cut_modulus_mm3`` the whole cut's (elsewhere the
    same numbers). ``stress_mpa`` is the governing stress; at a ``notch`` section (next to a
    concave corner, docs/notch.md) it is the peak at the corner, ``nominal_stress_mpa`` the beam
    stress, ``stress_concentration`` Kt (1 elsewhere) and ``notch_radius_mm`` the corner radius
    used (null elsewhere). An object without section geometry (no ``section_center``) gives ``[]``."""
    if not hasattr(a, "section_center"):
        return []
    n = len(a.stress)
    param = getattr(a, "section_param", None)
    allow = getattr(a, "section_allowable", None)
    ratio = getattr(a, "stress_ratio", None)
    across = getattr(a, "across_layers", None)
    cut_area = getattr(a, "section_cut_area", None)
    cut_modulus = getattr(a, "section_cut_modulus", None)
    none = [None] * n
    bones = np.asarray(a.section_bone, dtype=np.int64).tolist()
    cols = {
        "param_mm": _finite_list(param) if param is not None else none,
        "center_mm": _finite_list(a.section_center),
        "normal": _finite_list(a.section_normal),
        "area_mm2": _finite_list(a.section_area),
        "modulus_mm3": _finite_list(a.section_modulus),
        "cut_area_mm2": _finite_list(a.section_area if cut_area is None else cut_area),
        "cut_modulus_mm3": _finite_list(a.section_modulus if cut_modulus is None
                                        else cut_modulus),
        "moment_arm_mm": _finite_list(a.moment_arm),
        "moment_nmm": _finite_list(a.moment),
        "stress_mpa": _finite_list(a.stress),
        "nominal_stress_mpa": _finite_list(getattr(a, "nominal_stress", a.stress)),
        "stress_concentration": _finite_list(getattr(a, "stress_concentration",
                                                     np.ones(n))),
        "notch_radius_mm": _finite_list(getattr(a, "notch_radius", np.full(n, np.nan))),
        "allowable_mpa": _finite_list(allow) if allow is not None else none,
        "stress_ratio": _finite_list(ratio) if ratio is not None else none,
        "thickness_mm": _finite_list(a.section_thickness)
        if hasattr(a, "section_thickness") else none,
    }
    # the printed section (issue 31): absent fields (an engine without print profiles) -> the
    # solid modulus is the modulus, the areas null
    printed = {key: _finite_list(getattr(a, field)) if getattr(a, field, None) is not None
               else none for key, field in PRINTED_SECTION_FIELDS.items()}
    if getattr(a, "section_solid_modulus", None) is None:
        printed["solid_modulus_mm3"] = cols["modulus_mm3"]
    cols.update(printed)
    culled = np.asarray(a.culled, dtype=bool).tolist()
    weak = np.asarray(a.weak, dtype=bool).tolist()
    limit = (none if across is None else
             ["across layers" if x else "along layers"
              for x in np.asarray(across, dtype=bool).tolist()])
    # flags: most sections have none; names and reasons only where some bit is set
    flagged = (np.flatnonzero(np.asarray(a.section_flags)) if hasattr(a, "flag_names")
               else np.zeros(0, np.int64))
    names = {int(i): a.flag_names(int(i)) for i in flagged}
    reasons = ({int(i): a.flag_reasons(int(i)) for i in flagged}
               if hasattr(a, "flag_reasons") else {})
    # one dict per section, its values taken column by column in the row's key order
    order = ("param_mm", "center_mm", "normal", "area_mm2", "modulus_mm3", "solid_modulus_mm3",
             "wall_area_mm2", "skin_area_mm2", "infill_area_mm2", "cut_area_mm2",
             "cut_modulus_mm3", "moment_arm_mm", "moment_nmm", "stress_mpa", "nominal_stress_mpa",
             "stress_concentration", "notch_radius_mm", "culled", "weak", "allowable_mpa",
             "stress_ratio", "limit", "thickness_mm")
    cols.update(culled=culled, weak=weak, limit=limit)
    rows = []
    for i, values in enumerate(zip(*(cols[k] for k in order))):
        b = bones[i]
        row = {"index": i, "bone": bone_names[b], "bone_index": b}
        row.update(zip(order, values))
        row["flags"] = names.get(i, [])
        row["reasons"] = reasons.get(i, [])
        rows.append(row)
    return rows


def printability(a, bone_names) -> dict:
    """What the print cannot do, apart from overloading: ``too_thin`` (sections thinner than the
    minimum printable thickness: bone, position mm, thickness mm, reason), ``unreliable``
    (sections no material could be tied to) and ``loose_pieces`` (vertex count, first vertex
    index, the bone most of its vertices follow, and the vertex indices of each shell that would
    fall off; also ``Analysis.loose_pieces``)."""
    out = {"too_thin": [], "unreliable": [], "loose_pieces": []}
    flags = getattr(a, "section_flags", None)
    if flags is None or not hasattr(a, "flag_reasons"):
        return out
    from . import SECTION_FLAGS

    for i in np.flatnonzero(flags & SECTION_FLAGS["too_thin"]):
        b = int(a.section_bone[i])
        out["too_thin"].append({
            "bone": bone_names[b], "section": int(i), "param_mm": finite(a.section_param[i]),
            "thickness_mm": finite(a.section_thickness[i]),
            "reason": next(r for n, r in zip(a.flag_names(i), a.flag_reasons(i))
                           if n == "too_thin")})
    for i in np.flatnonzero(flags & SECTION_FLAGS["unreliable"]):
        b = int(a.section_bone[i])
        out["unreliable"].append({"bone": bone_names[b], "section": int(i),
                                  "param_mm": finite(a.section_param[i])})
    vertex_bone = getattr(a, "vertex_bone", None)
    for piece in getattr(a, "loose_pieces", []):
        piece = np.asarray(piece, dtype=np.int64)
        bone = None
        if vertex_bone is not None and len(piece):
            vb = np.asarray(vertex_bone, dtype=np.int64)[piece]
            vb = vb[(vb >= 0) & (vb < len(bone_names))]
            if len(vb):
                bone = bone_names[int(np.bincount(vb).argmax())]
        out["loose_pieces"].append({"vertices": len(piece),
                                    "first_vertex": int(piece[0]) if len(piece) else None,
                                    "bone": bone,
                                    "vertex_indices": [int(v) for v in piece]})
    return out


def loose_pieces_sentence(pieces: list) -> str:
    """One plain sentence naming the loose pieces of a report (``report["loose_pieces"]``), e.g.
    "2 loose pieces would fall off the print: 24 vertices at bone 'eye.L', 8 vertices"; "" when
    there are none."""
    if not pieces:
        return ""
    n = len(pieces)
    names = [f"{p['vertices']} vertices" + (f" at bone '{p['bone']}'" if p.get("bone") else "")
             for p in pieces[:5]]
    more = f" and {n - 5} more" if n > 5 else ""
    return (f"{n} loose piece{'s' if n != 1 else ''} would fall off the print: "
            + ", ".join(names) + more)


def build_report(*, analysis, bone_names, allowable_mpa: float, settings: dict,
                 front_end: str, model: str, object_name: str | None = None,
                 armature_name: str | None = None, mm_per_unit: float = 1.0,
                 vertices: int | None = None, faces: int | None = None,
                 seconds: float | None = None, correction=None, corrected_analysis=None,
                 output: str | None = None, print_profile=None,
                 section_table: bool = True) -> dict:
    """The JSON report (schema :data:`SCHEMA_VERSION`) of an analysis or a correction.

    ``analysis``: the ``osteon.Analysis`` of the model as it was. With a correction
    (``osteon.Correction``), ``corrected_analysis`` is the state after it (default
    ``correction.after``), which ``max_stress_mpa``, ``bones`` ... describe; ``weak_bones`` then
    lists every bone weak before or after or scaled, with its ``scale``, its stress now and
    before.
    ``settings``: :meth:`osteon.settings.Settings.as_dict` (or the front end's own dict);
    ``mm_per_unit``: mm of the print per model unit (file unit or Blender unit);
    ``print_profile``: the :class:`osteon.profiles.PrintProfile` analysed with (default: the
    analysis's own ``print_profile``, else the one ``settings`` names,
    :func:`osteon.profiles.profile_of`), echoed as ``print_profile``.
    ``section_table=False``: ``section_table`` is None, to be filled with :func:`section_rows`
    when it is needed (Live's per-update report: the panel reads the bones, not every section;
    more than half of a report's time is that table).
    """
    if correction is not None and corrected_analysis is None:
        corrected_analysis = correction.after
    shown = corrected_analysis if corrected_analysis is not None else analysis
    scale = None if correction is None else np.asarray(correction.bone_scale, dtype=np.float64)
    d = doubt.section_doubt(shown)     # once: the rows, the counts and the worst read it
    rows = _analysis_table(shown, bone_names, allowable_mpa, scale, d)
    if correction is None:
        weak_bones = [{"bone": r["bone"], "max_stress_mpa": r["max_stress_mpa"],
                       "ratio": r["ratio"], "stress_mpa": r["stress_mpa"],
                       "allowable_mpa": r["allowable_mpa"], "limit": r["limit"],
                       "scale": r["scale"], "weak": True,
                       "stress_concentration": r["stress_concentration"]}
                      for r in rows if r["weak"]]
        before_rows = None
    else:
        before_rows = _analysis_table(analysis, bone_names, allowable_mpa)
        before = {r["bone"]: r for r in before_rows}
        weak_bones = [
            {"bone": r["bone"], "max_stress_mpa": r["max_stress_mpa"], "ratio": r["ratio"],
             "stress_mpa": r["stress_mpa"], "allowable_mpa": r["allowable_mpa"],
             "limit": r["limit"], "scale": r["scale"], "weak": r["weak"],
             "stress_concentration": r["stress_concentration"],
             "max_stress_before_mpa": before[r["bone"]]["max_stress_mpa"]
             if r["bone"] in before else None}
            # weak before or after, or scaled (a bone can become weak during the loop, when
            # re-skinning a neighbour changes its corner or junction sections)
            for r in rows if r["weak"] or (r["bone"] in before and before[r["bone"]]["weak"])
            or (r["scale"] is not None and abs(float(r["scale"]) - 1.0) > 1e-12)
        ]
    max_stress = finite(shown.max_stress)
    report = {
        "schema_version": SCHEMA_VERSION,
        "run": {"front_end": front_end, "osteon_version": _version(), "blender_version": None,
                "blend_file": None, "seconds": finite(seconds)},
        "model": str(model),
        "object": object_name,
        "armature": armature_name,
        "output": None if output is None else str(output),
        "units": dict(UNITS),
        "settings": dict(settings),
        "mm_per_model_unit": float(mm_per_unit),
        "vertices": None if vertices is None else int(vertices),
        "faces": None if faces is None else int(faces),
        "bone_names": list(bone_names),
        "force_n": finite(settings.get("force_n")),
        "allowable_stress_mpa": float(allowable_mpa),
        "max_stress_mpa": max_stress,
        "stress_ratio": None if max_stress is None else
        finite(getattr(shown, "max_stress_ratio", max_stress / float(allowable_mpa))),
        # FDM layers (docs/printing.md): the build direction in the model's frame and the layer /
        # in-plane strength; stress ratios use each section's angle to the build direction
        "build_direction": [float(x) for x in getattr(shown, "build_direction", (0, 0, 1))],
        "layer_strength_ratio": float(getattr(shown, "layer_strength_ratio", 1.0)),
        # how the part is printed (walls, skins, infill; docs/printing.md): the profile whose
        # printed sections the moduli and stresses below are
        "print_profile": _profile_dict(settings, print_profile
                                       if print_profile is not None
                                       else getattr(shown, "print_profile", None)),
        "safe_modulus_mm3": finite(shown.safe_modulus),
        "sections": len(shown.stress),
        "weak_sections": int(np.count_nonzero(shown.weak)),
        "culled_sections": int(np.count_nonzero(shown.culled)),
        "weak_bones": weak_bones,
        # the section that governs the verdict: the highest stress / ITS allowable (FDM layers:
        # across or along them), so that ratio == stress_mpa / allowable_mpa
        "worst": worst_of(rows),
        "bones": rows,
        # the CLI's name for ``bones`` before the schema had a version; same list
        "bone_results": rows,
        "section_table": section_rows(shown, bone_names) if section_table else None,
        "converged": (not any(r["weak"] for r in rows)) if correction is None
        else bool(correction.converged),
        "corrected": correction is not None,
        "correction": None,
        "max_stress_before_mpa": None,
        "bone_scale": None,
        "bone_scale_xz": None,
        "warnings": [],
        # reinforce instead of reshape (osteon.reinforce, docs/correction.md): filled by
        # reinforcement_section when the run reinforced
        "reinforcement": None,
    }
    # Printability, reported apart from the overloaded sections (issue 12).
    printable = printability(shown, bone_names)
    report["too_thin_sections"] = printable["too_thin"]
    report["unreliable_sections"] = printable["unreliable"]
    report["loose_pieces"] = printable["loose_pieces"]
    # junctions (docs/junctions.md): sections whose numbers are the core's, not the whole cut's
    report["junction_sections"] = [int(i) for i in np.flatnonzero(
        np.asarray(getattr(shown, "junction", np.zeros(len(shown.stress), bool))))]
    # what the numbers above do not cover (osteon.doubt): skipped sections, bones not analysed,
    # a maximum resting on a doubtful section
    report["skipped_sections"] = int(np.count_nonzero(d["skipped"]))
    report["doubtful_sections"] = int(np.count_nonzero(d["doubtful"]))
    report["skipped_by_flag"] = d["skipped_by_flag"]
    report["flagged_sections"] = d["by_flag"]
    report["not_analysed_share"] = doubt.NOT_ANALYSED_SHARE
    report["not_analysed_bones"] = [
        {"bone": r["bone"], "sections": r["sections"], "skipped_sections": r["skipped_sections"],
         "reason": r["reason"]} for r in rows if r["status"] == "not analysed"]
    report["max_stress_doubt"] = doubt.worst_section_doubt(shown, d)
    report["verdict"] = ("weak" if any(r["weak"] for r in rows) else
                         "not analysed" if report["not_analysed_bones"] or (
                             report["sections"] and report["max_stress_mpa"] is None) else "ok")
    report["doubt"] = doubt.summary_text(report) or None
    if correction is not None:
        rounds = correction.rounds
        sx = getattr(correction, "bone_scale_x", None)
        sz = getattr(correction, "bone_scale_z", None)
        before_max = finite(analysis.max_stress)
        report["max_stress_before_mpa"] = before_max
        report["bone_scale"] = [float(s) for s in scale]
        if sx is not None and sz is not None:
            report["bone_scale_xz"] = [[float(x), float(z)] for x, z in zip(sx, sz)]
        report["correction"] = {
            "rounds": len(rounds) if hasattr(rounds, "__len__") else int(rounds),
            "reason": str(getattr(correction, "reason", "")),
            "converged": bool(correction.converged),
            "max_stress_before_mpa": before_max,
            "max_stress_after_mpa": max_stress,
            "engine_max_stress_after_mpa": finite(correction.after.max_stress),
            "bone_scale": {bone_names[i]: float(s) for i, s in enumerate(scale) if s != 1.0},
            # pose scale X and Z of each scaled bone (they differ where a flat part was
            # thickened across its thickness only)
            "bone_scale_xz": None if sx is None or sz is None else {
                bone_names[i]: [float(sx[i]), float(sz[i])]
                for i in range(len(bone_names)) if sx[i] != 1.0 or sz[i] != 1.0},
            "before": {"max_stress_mpa": before_max,
                       "weak_sections": int(np.count_nonzero(analysis.weak)),
                       "bones": before_rows},
        }
    return report


def reinforcement_section(reinforcement, slicer: str | None = None,
                          project: str | None = None) -> dict:
    """The report's ``reinforcement`` of an ``osteon.Reinforcement``: the profile of the rest of
    the part, one row per region (bone, walls and infill before -> after, stress before ->
    after MPa, extra extruded volume mm³, z range mm), the sections solid cannot carry, the
    total extra volume and the slicer project written (``slicer``, ``project`` path)."""
    r = reinforcement
    return {
        "print_profile": r.profile.as_dict(),
        "regions": r.table(),
        "unfixable": [{"section": u["section"], "bone": u["bone"],
                       "stress_mpa": finite(u["stress_mpa"]), "ratio": finite(u["ratio"])}
                      for u in r.unfixable],
        "extra_volume_mm3": finite(r.extra_volume_mm3),
        "max_stress_before_mpa": finite(r.before.max_stress),
        "max_stress_after_mpa": finite(r.after.max_stress),
        "analyses": int(r.analyses),
        "slicer": slicer,
        "slicer_project": None if project is None else str(project),
    }


def _profile_dict(settings: dict, print_profile) -> dict:
    if print_profile is None:
        from .profiles import profile_of

        print_profile = profile_of(settings)
    return print_profile.as_dict() if hasattr(print_profile, "as_dict") else dict(print_profile)


def to_json(report: dict, indent: int = 1) -> str:
    """The report as JSON text; refuses NaN/inf (which :func:`finite` already removed)."""
    import json

    return json.dumps(report, indent=indent, allow_nan=False)


@functools.lru_cache(maxsize=1)
def _version() -> str:
    """The installed osteon's version (read once: the metadata lookup costs ~20 ms, and the
    Blender add-on's Live mode builds a report on every update)."""
    try:
        from importlib.metadata import version

        return version("osteon")
    except Exception:  # noqa: BLE001 - not installed as a distribution (e.g. vendored)
        from . import __version__

        return __version__
