"""Which sections the FEM check tests, and where osteon holds the model. Units: mm."""

from __future__ import annotations

import numpy as np


def hold_point(analysis, heads):
    """The point osteon holds: the head of the held bone (mm)."""
    b = int(getattr(analysis, "held_bone", 0))
    return np.asarray(heads, float)[max(b, 0)]


def pick_sections(
    analysis, heads, tails, n=4, vertices=None, per_bone=1, tiers=((1.5, 3.0), (0.75, 2.0)),
    junctions=False,
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
    junction_bit = 0
    if junctions:
        from .. import SECTION_FLAGS

        junction_bit = int(SECTION_FLAGS["junction"])
    if flags is not None:
        base &= np.asarray(flags) == junction_bit
    elif junctions:
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
        if junctions:
            ok &= np.abs(axial) >= k_arm * r
        idx = np.nonzero(ok)[0]
        idx = idx[np.argsort(-stress[idx])]
        for i in idx:
            b = int(bone[i])
            if i in taken or count.get(b, 0) >= per_bone:
                continue
            count[b] = count.get(b, 0) + 1
            taken.add(int(i))
            out.append(
                {
                    "index": int(i),
                    "bone": b,
                    "center": centers[i],
                    "normal": np.asarray(a.section_normal[i], float),
                    "load_point": np.asarray(a.load_point[i], float),
                    "moment_arm": float(arm[i]),
                    "osteon_stress": float(stress[i]),
                    "area": float(area[i]),
                    "tier": tier,
                    "slenderness": float(arm[i] / r[i]),
                    "end_distance": float(end[i] / r[i]),
                }
            )
            if junctions:
                w_cut = float(np.asarray(a.section_cut_modulus)[i])
                out[-1]["junction"] = True
                out[-1]["osteon_cut_stress"] = float(a.moment[i] / w_cut)
            if len(out) >= n:
                return out
    return out
