"""Which sections the FEM check tests, and where osteon holds the model. Units: mm."""

from __future__ import annotations

import numpy as np


def hold_point(analysis, heads):
    """The point osteon holds: the head of the held bone (mm)."""
    b = int(getattr(analysis, "held_bone", 0))
    return np.asarray(heads, float)[max(b, 0)]


def pick_sections(
    analysis, heads, tails, n=4, vertices=None, per_bone=1, tiers=((1.5, 3.0), (0.75, 2.0)),
    junctions=False, notch=False,
):
    """Choose up to ``n`` sections for the FEM check, at most ``per_bone`` per bone, highest
    stress first, where beam theory is meant to hold: interior sections (not at joints or bone
    ends, no flags) whose centre is outside the held region. ``tiers`` are tried in turn,
    ``(end distance, slenderness)``: a section qualifies when it is at least
    ``end distance`` × r (and half an interval) from both ends of its bone and its moment arm is
    at least ``slenderness`` × r, with r = √(area/π). Returns section dicts for
    :func:`cross_check`, each with its ``tier`` (0 = strictest), ``slenderness`` = arm / r and
    ``end_distance`` = distance to the nearer bone end / r.

    ``junctions=True`` picks only ``junction`` sections (no other flag; docs/junctions.md),
    with r from the core's area, to check the core against FEM read on the same plane; their
    dicts also carry ``junction`` and ``osteon_cut_stress`` (the stress with the whole cut).
    ``notch=True`` picks only ``notch`` sections (the corner model's; docs/notch.md; a
    ``junction`` flag may come with it, no other), to check the governing stress against FEM's
    peak by the corner (``fem.peaks``); same rule on the load point as junctions.

    Every dict carries what the corner check reports: ``nominal_stress``,
    ``stress_concentration``, ``notch_radius`` (None where none), ``flags`` and ``interval``.

    Junction sections sit near joints, where the downstream part may fold back: they are also
    required to have the load point at least ``slenderness`` × r off the plane (along the
    normal), so that the section is a beam section between the support and the load, not the
    plane through the load's point of application (Saint-Venant: the FEM σ there is the local
    stress under the load).
    """
    a = analysis
    heads, tails = np.asarray(heads, float), np.asarray(tails, float)
    stress = np.asarray(a.stress, float)
    bone = np.asarray(a.section_bone)
    L = np.linalg.norm(tails - heads, axis=1)[bone]
    area = np.asarray(a.section_area, float)
    r = np.sqrt(np.where(area > 0, area, np.nan) / np.pi)
    t = np.asarray(getattr(a, "section_param", np.full(len(stress), np.nan)), float)
    if not np.all(np.isfinite(t)):
        u = (tails - heads)[bone]
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        t = np.einsum("ij,ij->i", np.asarray(a.section_center) - heads[bone], u)
    interval = float(getattr(a, "interval", 2.0))
    arm = np.asarray(a.moment_arm, float)
    # the load point's distance from the section plane, mm
    axial = np.einsum("ij,ij->i", np.asarray(a.load_point, float) - np.asarray(a.section_center, float),
                      np.asarray(a.section_normal, float))
    base = np.isfinite(stress) & np.isfinite(r)
    kind = getattr(a, "section_kind", None)
    if kind is not None:
        base &= np.asarray(kind) == 0
    flags = getattr(a, "section_flags", None)
    from .. import SECTION_FLAGS

    junction_bit = int(SECTION_FLAGS["junction"]) if junctions else 0
    if flags is not None and notch:
        fl = np.asarray(flags).astype(np.int64)
        nb = int(SECTION_FLAGS["notch"])
        base &= ((fl & nb) != 0) & ((fl | nb | int(SECTION_FLAGS["junction"]))
                                    == nb | int(SECTION_FLAGS["junction"]))
    elif flags is not None:
        base &= np.asarray(flags) == junction_bit
    elif junctions or notch:
        base &= False
    hp = hold_point(a, heads)
    depth = 0.0
    if vertices is not None:
        depth = float(np.min(np.linalg.norm(np.asarray(vertices, float) - hp, axis=1)))
    centers = np.asarray(a.section_center, float)
    base &= np.linalg.norm(centers - hp, axis=1) >= 1.25 * depth + 2.0 * r
    end = np.minimum(t, L - t)
    out, count, taken = [], {}, set()
    for tier, (k_end, k_arm) in enumerate(tiers):
        ok = base & (end >= np.maximum(k_end * r, 0.5 * interval)) & (arm >= k_arm * r)
        if junctions or notch:
            ok &= np.abs(axial) >= k_arm * r
        idx = np.nonzero(ok)[0]
        idx = idx[np.argsort(-stress[idx])]
        for i in idx:
            b = int(bone[i])
            if i in taken or count.get(b, 0) >= per_bone:
                continue
            count[b] = count.get(b, 0) + 1
            taken.add(int(i))
            out.append(section_dict(a, i, tier=tier, slenderness=float(arm[i] / r[i]),
                                    end_distance=float(end[i] / r[i])))
            if junctions:
                w_cut = float(np.asarray(a.section_cut_modulus)[i])
                out[-1]["junction"] = True
                out[-1]["osteon_cut_stress"] = float(a.moment[i] / w_cut)
            if len(out) >= n:
                return out
    return out


def section_dict(analysis, i, **extra):
    """The FEM check's dict of section ``i`` (:func:`cross_check`'s input), with the corner
    model's values (module docstring of :func:`pick_sections`)."""
    a = analysis
    i = int(i)
    rad = float(np.asarray(getattr(a, "notch_radius", [np.nan] * (i + 1)), float)[i])
    kt = getattr(a, "stress_concentration", None)
    nominal = getattr(a, "nominal_stress", None)
    flags = getattr(a, "section_flags", None)
    return {
        "index": i,
        "bone": int(np.asarray(a.section_bone)[i]),
        "center": np.asarray(a.section_center[i], float),
        "normal": np.asarray(a.section_normal[i], float),
        "load_point": np.asarray(a.load_point[i], float),
        "moment_arm": float(np.asarray(a.moment_arm)[i]),
        "osteon_stress": float(np.asarray(a.stress)[i]),
        "area": float(np.asarray(a.section_area)[i]),
        "nominal_stress": float(np.asarray(nominal)[i]) if nominal is not None
        else float(np.asarray(a.stress)[i]),
        "stress_concentration": float(np.asarray(kt)[i]) if kt is not None else 1.0,
        "notch_radius": rad if np.isfinite(rad) else None,
        "flags": int(np.asarray(flags)[i]) if flags is not None else 0,
        "interval": float(getattr(a, "interval", 2.0)),
        **extra,
    }


def parse_section_ids(texts, bone_names):
    """``--section`` values -> section indices: ``N`` (the section's index, as the CLI's tables
    and JSON number them) or ``BONE:N`` (the same index, checked to lie on bone BONE, by name).
    Bad values raise ValueError (checked against the analysis by :func:`chosen_sections`)."""
    out = []
    for text in texts:
        bone, sep, num = str(text).rpartition(":")
        try:
            idx = int(num)
        except ValueError:
            raise ValueError(f"--section {text!r}: expected N or BONE:N (N the section's index)") from None
        if idx < 0:
            raise ValueError(f"--section {text!r}: the index must be >= 0")
        if sep and bone not in bone_names:
            raise ValueError(f"--section {text!r}: no bone named {bone!r}")
        out.append((idx, bone_names.index(bone) if sep else None, str(text)))
    return out


def chosen_sections(analysis, ids):
    """Section dicts for the FEM check of the chosen sections ``ids`` (indices, or the
    (index, bone or None, text) triples of :func:`parse_section_ids`), flagged or not.
    ValueError for an index out of range, on another bone, of a section without a stress
    (NaN: open, empty or outside), or given twice."""
    a = analysis
    n = len(a.stress)
    bone = np.asarray(a.section_bone)
    out, seen = [], set()
    for item in ids:
        idx, want, text = item if isinstance(item, tuple) else (int(item), None, str(item))
        if not 0 <= idx < n:
            raise ValueError(f"--section {text}: no section {idx} (the analysis has {n}, 0 .. "
                             f"{n - 1})")
        if want is not None and int(bone[idx]) != want:
            raise ValueError(f"--section {text}: section {idx} lies on bone "
                             f"{a.bone_names[int(bone[idx])]!r}")
        if not (np.isfinite(a.stress[idx]) and a.section_area[idx] > 0):
            raise ValueError(f"--section {text}: section {idx} has no stress to check")
        if idx in seen:
            raise ValueError(f"--section {text}: section {idx} given twice")
        seen.add(idx)
        out.append(section_dict(a, idx))
    return out
