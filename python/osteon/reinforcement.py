"""Reinforce instead of reshape: more walls and denser infill where the part is weak.

:func:`reinforce` finds the weak regions of a print (runs of weak sections along one bone, with
the part printed as the print profile says, docs/printing.md) and gives each the cheapest change
of its print settings that brings every one of its sections under the allowable:

1. more perimeters, one at a time, up to ``max_perimeters`` (the profile's infill kept);
2. if that is not enough, denser infill (``INFILL_STEPS``, up to 100 % = solid), each step with
   the fewest perimeters that then suffice;
3. sections that even solid cannot carry are ``unfixable``: only thickening helps them
   (``correct(..., reinforce_first=True)`` does that).

Walls come first because they put material at the section's outer fibre, where bending
stress is largest, and the slicer prints them in every layer.

Cost (reported per region, mm³): the extra extruded volume, Σ over the region's sections of
(extruded area with the region's settings − with the profile's) × ``interval``; the extruded area
of a section is walls + skins + infill area × infill density (the printed section's
``section_wall_area``, ``section_skin_area``, ``section_infill_area``). Each section stands for
``interval`` mm of the bone around it.

Exactness: a section's load and moment come from the mesh, the skeleton and the force, not from
how it is printed, and a section's printed modulus depends only on its own cut; so analysing the
whole part with a candidate profile and reading the region's sections gives exactly what the
region printed with that candidate would carry (``tests/python/test_reinforce.py`` checks the
moments are equal across profiles).

Each region also gets a modifier volume (:func:`modifier_volume`): a closed convex mesh around
the region's sections, grown by ``margin`` mm, which the slicer project (:mod:`osteon.slicer3mf`)
carries with the region's settings.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import _api
from ._api import SECTION_FLAGS, Correction, analyze, correct
from .profiles import PrintProfile, get_profile

#: Infill densities tried (fractions) once walls alone are not enough; 1.0 is solid.
INFILL_STEPS = (0.25, 0.4, 0.6, 0.8, 1.0)

#: 26 unit directions (cube corners, edges, faces): the modifier's margin is grown along them.
_DIRS = np.array([(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1)
                  if (i, j, k) != (0, 0, 0)], dtype=float)
_DIRS /= np.linalg.norm(_DIRS, axis=1)[:, None]


def convex_volume(points: np.ndarray, margin: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """A closed, outward-oriented triangle mesh (vertices (n,3) mm, faces (m,3)) of the convex
    hull of ``points`` grown by ``margin`` mm (every point within ``margin`` · 0.92 of the hull
    is inside: the 26 growth directions are at most 22.5° from any direction)."""
    from scipy.spatial import ConvexHull

    p = np.asarray(points, dtype=float).reshape(-1, 3)
    if margin > 0.0:
        p = (p[:, None, :] + margin * _DIRS[None, :, :]).reshape(-1, 3)
    hull = ConvexHull(p)
    used = np.unique(hull.simplices)
    remap = np.full(len(p), -1)
    remap[used] = np.arange(len(used))
    v = p[used]
    f = remap[hull.simplices]
    centre = v.mean(0)
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    inward = np.einsum("ij,ij->i", np.cross(b - a, c - a), a - centre) < 0.0
    f[inward] = f[inward][:, ::-1]
    return v, f.astype(np.int64)


def modifier_volume(analysis: Any, sections: np.ndarray,
                    margin: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """The modifier volume of a region: the convex hull of its sections' loops, each end
    section's loops also moved half an ``interval`` outward along the bone (a section stands for
    ``interval`` mm), grown by ``margin`` mm. ``analysis`` needs ``keep_outlines=True``."""
    loops = analysis.section_loops
    if loops is None:
        raise ValueError("the analysis has no section outlines (analyse with keep_outlines=True)")
    sections = np.asarray(sections, dtype=np.int64)
    pts = [lp for s in sections for lp in loops[s]]
    if not pts:
        raise ValueError("the region's sections have no outline")
    params = analysis.section_param[sections]
    half = 0.5 * float(analysis.interval)
    for s, sign in ((sections[np.argmin(params)], -1.0), (sections[np.argmax(params)], 1.0)):
        n = np.asarray(analysis.section_normal[s], dtype=float)
        # the normal points along the bone (head -> tail): the head end moves back, the tail on
        for lp in loops[s]:
            pts.append(lp + sign * half * n)
    return convex_volume(np.concatenate(pts), margin)


def weak_regions(analysis: Any, merge_gap: int = 1) -> list[np.ndarray]:
    """Runs of weak sections along each bone, in bone order (index arrays into the analysis).
    Two runs on one bone separated by at most ``merge_gap`` sections that hold are one region
    (one modifier instead of a patchwork)."""
    regions = []
    weak = np.asarray(analysis.weak, dtype=bool)
    valid = analysis.valid
    for b in np.unique(analysis.section_bone[weak]):
        idx = np.flatnonzero((analysis.section_bone == b) & valid)
        idx = idx[np.argsort(analysis.section_param[idx], kind="stable")]
        run: list[int] = []
        gap = 0
        for i in idx:
            if weak[i]:
                run.append(int(i))
                gap = 0
            elif run:
                gap += 1
                if gap > merge_gap:
                    regions.append(np.array(run))
                    run, gap = [], 0
        if run:
            regions.append(np.array(run))
    return regions


def extruded_area(analysis: Any, profile: PrintProfile, sections: np.ndarray) -> np.ndarray:
    """(n,) mm²: what the printer extrudes in each section (walls + skins + infill area ×
    infill density); the solid area for a solid profile."""
    if profile.is_solid or getattr(analysis, "section_wall_area", None) is None:
        return np.asarray(analysis.section_area, dtype=float)[sections]
    return (analysis.section_wall_area[sections] + analysis.section_skin_area[sections]
            + profile.infill * analysis.section_infill_area[sections])


@dataclass
class Reinforcement:
    """Result of :func:`reinforce`.

    ``regions``: one dict per weak region: ``bone`` (name), ``bone_index``, ``sections`` (indices
    into ``before``/``after``), ``extent_mm`` (start, end) along the bone from its head,
    ``z_range`` (lowest, highest) mm of the region's modifier along the build direction,
    ``perimeters`` and ``infill`` (the region's settings: count, fraction), ``perimeters_before``,
    ``infill_before``, ``stress_before_mpa`` and ``stress_after_mpa`` (the region's largest),
    ``ratio_before``/``ratio_after`` (stress / allowable), ``extra_volume_mm3``, ``fixed``
    (every section under the allowable), ``vertices`` (n,3) mm and ``faces`` (m,3): the
    modifier volume. ``before``: the analysis with the profile everywhere; ``after``: with each
    region's settings in its sections; ``unfixable``: sections solid cannot carry
    (``{section, bone, stress_mpa, ratio}``); ``profile``: the profile of the rest of the part.
    """

    regions: list
    before: Any
    after: Any
    unfixable: list
    profile: PrintProfile
    vertices: np.ndarray = field(repr=False)
    faces: np.ndarray = field(repr=False)
    build_direction: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    analyses: int = 0

    @property
    def extra_volume_mm3(self) -> float:
        """Extra extruded volume of all regions, mm³."""
        return float(sum(r["extra_volume_mm3"] for r in self.regions))

    def write_3mf(self, path, slicer: str = "prusaslicer", **kw) -> dict:
        """Write the slicer project (:func:`osteon.slicer3mf.write_3mf`): the model on the bed
        in the build direction and one modifier volume per region with its settings."""
        from .slicer3mf import write_3mf

        return write_3mf(path, self.vertices, self.faces, self.regions, self.profile,
                         self.build_direction, slicer, **kw)

    def table(self) -> list[dict]:
        """One JSON-ready row per region (no meshes): the report's ``reinforcement``."""
        from .report import finite

        rows = []
        for r in self.regions:
            rows.append({
                "bone": r["bone"], "sections": len(r["sections"]),
                "extent_mm": [finite(x) for x in r["extent_mm"]],
                "z_range_mm": [finite(x) for x in r["z_range"]],
                "perimeters_before": r["perimeters_before"], "perimeters": r["perimeters"],
                "infill_before": r["infill_before"], "infill": r["infill"],
                "stress_before_mpa": finite(r["stress_before_mpa"]),
                "stress_after_mpa": finite(r["stress_after_mpa"]),
                "ratio_before": finite(r["ratio_before"]), "ratio_after": finite(r["ratio_after"]),
                "extra_volume_mm3": finite(r["extra_volume_mm3"]), "fixed": r["fixed"]})
        return rows

    def __repr__(self) -> str:
        return (f"Reinforcement({len(self.regions)} regions, {len(self.unfixable)} unfixable "
                f"sections, +{self.extra_volume_mm3:.0f} mm³, max stress "
                f"{self.before.max_stress:.3g} -> {self.after.max_stress:.3g} MPa)")


_SECTION_FIELDS = ("section_modulus", "stress", "stress_ratio", "weak", "culled",
                   "section_solid_modulus", "section_wall_area", "section_skin_area",
                   "section_infill_area")


def vertex_stress(analysis: Any, vertices: np.ndarray, bones, base: np.ndarray) -> np.ndarray:
    """(V,) MPa: ``base`` with the vertices of ``bones`` given the stress of ``analysis``'s
    sections as the engine does (analysis_vertex_stress.cpp): along its bone, linear between the
    neighbouring sections, the end ones beyond them; unreliable and too-thin sections left out,
    several at one place the worst; loose pieces stay 0. The bone's frame (head, unit axis) comes
    from the sections' own ``section_point`` and ``section_param``."""
    out = np.array(base, dtype=float, copy=True)
    v = np.asarray(vertices, dtype=float)
    skip = SECTION_FLAGS["unreliable"] | SECTION_FLAGS["too_thin"]
    loose = np.zeros(len(v), bool)
    for piece in analysis.loose_pieces:
        loose[np.asarray(piece, dtype=np.int64)] = True
    for b in bones:
        idx = np.flatnonzero((analysis.section_bone == b) & analysis.valid
                             & ((analysis.section_flags & skip) == 0))
        if len(idx) == 0:
            continue
        idx = idx[np.argsort(analysis.section_param[idx], kind="stable")]
        p, st = analysis.section_param[idx], analysis.stress[idx]
        lo, hi = idx[0], idx[-1]
        if p[-1] - p[0] <= 0.0:
            continue  # one place only: the frame is unknown, keep the base
        axis = (analysis.section_point[hi] - analysis.section_point[lo]) / (p[-1] - p[0])
        head = analysis.section_point[lo] - p[0] * axis
        keep = np.r_[True, np.diff(p) > 1e-9 * (1.0 + np.abs(p[1:]))]
        groups = np.cumsum(keep) - 1
        worst = np.full(int(groups[-1]) + 1, -np.inf)
        np.maximum.at(worst, groups, st)
        sel = np.flatnonzero((analysis.vertex_bone == b) & ~loose)
        out[sel] = np.interp((v[sel] - head) @ axis, p[keep], worst)
    return out


def _combine(before: Any, picks: list[tuple[np.ndarray, Any]], vertices: np.ndarray) -> Any:
    """``before`` with each region's sections taken from its chosen analysis (and the
    vertices of the regions' bones coloured by them)."""
    changes = {}
    for name in _SECTION_FIELDS:
        arr = getattr(before, name, None)
        if arr is None:
            continue
        arr = np.array(arr, copy=True)
        for idx, a in picks:
            arr[idx] = getattr(a, name)[idx]
        changes[name] = arr
    bones = sorted({int(before.section_bone[idx[0]]) for idx, _ in picks})
    changes["vertex_stress"] = vertex_stress(
        dataclasses.replace(before, **changes), vertices, bones, before.vertex_stress)
    after = dataclasses.replace(before, **changes)
    ok = np.flatnonzero(after.valid & ~after.too_thin)
    if len(ok):
        w = ok[np.argmax(after.stress[ok])]
        after.max_stress, after.weakest_section = float(after.stress[w]), int(w)
        after.max_stress_ratio = float(np.max(after.stress_ratio[ok]))
    return after


class _Search:
    """Analyses of the whole part with candidate profiles, each run once (cached)."""

    def __init__(self, run, base: PrintProfile):
        self.run, self.base, self.cache = run, base, {}

    def profile(self, perimeters: int, infill: float) -> PrintProfile:
        return self.base.with_changes(perimeters=int(perimeters), infill=float(infill))

    def analysis(self, perimeters: int, infill: float):
        key = (int(perimeters), round(float(infill), 6))
        if key not in self.cache:
            self.cache[key] = self.run(self.profile(*key))
        return self.cache[key]

    def holds(self, idx: np.ndarray, perimeters: int, infill: float) -> bool:
        return not bool(np.any(self.analysis(perimeters, infill).weak[idx]))

    def fewest_perimeters(self, idx, low: int, high: int, infill: float) -> int | None:
        """The fewest perimeters in [low, high] that hold the region at ``infill`` (more walls
        never weaken a section: bisection), or None."""
        if not self.holds(idx, high, infill):
            return None
        while low < high:
            mid = (low + high) // 2
            if self.holds(idx, mid, infill):
                high = mid
            else:
                low = mid + 1
        return high


def _choose(search: _Search, idx: np.ndarray, max_perimeters: int) -> tuple[int, float, bool]:
    """(perimeters, infill, fixed) for one region, by the rule of the module docstring."""
    base = search.base
    top = max(max_perimeters, base.perimeters)
    p = search.fewest_perimeters(idx, base.perimeters + 1, top, base.infill) \
        if top > base.perimeters else None
    if p is not None:
        return p, base.infill, True
    for fill in INFILL_STEPS:
        if fill <= base.infill:
            continue
        p = search.fewest_perimeters(idx, base.perimeters, top, fill)
        if p is not None:
            return p, fill, True
    return base.perimeters, 1.0, False  # solid: the most printing can do


def reinforce(vertices: Any, faces: Any, skeleton: Any, weights: Any = None, *, force: float,
              allowable_stress: float, print_profile: Any, build_direction: Any = (0.0, 0.0, 1.0),
              interval: float, root: int | str | None = None, max_perimeters: int = 10,
              margin: float = 1.0, **options: Any) -> Reinforcement:
    """More walls and denser infill where the printed part is weak (module docstring: the rule,
    the cost, why re-analysing the whole part per candidate is exact).

    Arguments as :func:`osteon.analyze` (mm, N, MPa); ``print_profile``: an FDM
    :class:`~osteon.profiles.PrintProfile` or a preset name; ``max_perimeters``: the most walls
    a region gets before its infill is raised; ``margin`` mm: how far each modifier volume
    reaches beyond its sections; ``options``: further :func:`osteon.analyze` keywords
    (``weights`` handling, ``layer_strength_ratio``, ``junctions``, ...)."""
    profile = get_profile(print_profile)
    if profile.kind != "fdm":
        raise ValueError("reinforce needs an FDM print profile (walls and infill to change), "
                         f"got {profile.kind!r}")
    if isinstance(max_perimeters, bool) or int(max_perimeters) != max_perimeters \
            or not 1 <= int(max_perimeters) <= 100:
        raise ValueError(f"max_perimeters must be a whole number 1..100, got {max_perimeters!r}")
    if not (float(margin) >= 0.0 and math.isfinite(float(margin))):
        raise ValueError(f"margin must be a finite number >= 0 mm, got {margin!r}")
    v = np.asarray(vertices, dtype=float)
    f = np.asarray(faces)

    def run(prof: PrintProfile, outlines: bool = False):
        return analyze(v, f, skeleton, weights, force=force, allowable_stress=allowable_stress,
                       interval=interval, root=root, build_direction=build_direction,
                       print_profile=prof, keep_outlines=outlines, **options)

    before = run(profile, outlines=True)
    search = _Search(run, profile)
    search.cache[(profile.perimeters, round(profile.infill, 6))] = before
    bdir = np.asarray(before.build_direction, dtype=float)
    regions, picks, unfixable = [], [], []
    base_area = None
    for idx in weak_regions(before):
        p, fill, fixed = _choose(search, idx, int(max_perimeters))
        chosen = search.analysis(p, fill)
        picks.append((idx, chosen))
        if base_area is None:
            base_area = extruded_area(before, profile, np.arange(before.num_sections))
        extra = float(np.sum(extruded_area(chosen, search.profile(p, fill), idx)
                             - base_area[idx]) * before.interval)
        mv, mf = modifier_volume(before, idx, float(margin))
        b = int(before.section_bone[idx[0]])
        heights = mv @ (bdir / np.linalg.norm(bdir))
        regions.append({
            "bone": before.bone_names[b], "bone_index": b, "sections": idx,
            "extent_mm": (float(before.section_param[idx].min()),
                          float(before.section_param[idx].max())),
            "z_range": (float(heights.min()), float(heights.max())),
            "perimeters": int(p), "infill": float(fill),
            "perimeters_before": profile.perimeters, "infill_before": profile.infill,
            "stress_before_mpa": float(np.max(before.stress[idx])),
            "stress_after_mpa": float(np.max(chosen.stress[idx])),
            "ratio_before": float(np.max(before.stress_ratio[idx])),
            "ratio_after": float(np.max(chosen.stress_ratio[idx])),
            "extra_volume_mm3": extra, "fixed": fixed, "vertices": mv, "faces": mf})
        if not fixed:
            unfixable += [{"section": int(s), "bone": before.bone_names[b],
                           "stress_mpa": float(chosen.stress[s]),
                           "ratio": float(chosen.stress_ratio[s])}
                          for s in idx if chosen.weak[s]]
    after = _combine(before, picks, v)
    return Reinforcement(regions=regions, before=before, after=after, unfixable=unfixable,
                         profile=profile, vertices=v, faces=f, build_direction=bdir,
                         analyses=len(search.cache))


def reinforce_then_correct(vertices: Any, faces: Any, skeleton: Any, weights: Any = None, *,
                           print_profile: Any, max_perimeters: int = 10, margin: float = 1.0,
                           **correct_options: Any) -> Any:
    """``correct(..., reinforce_first=True)``: reinforce (:func:`reinforce`), then thicken only
    what reinforcement cannot fix, and return the :class:`osteon.Correction` with its
    ``reinforcement``.

    What solid cannot carry is exactly what a correction of the *solid* part thickens (a solid
    section is the strongest any print of it can be), so the thickening runs on the solid part
    (``osteon.correct`` without a print profile) and leaves alone the bones that walls or
    infill can save (except where re-skinning a thickened bone changes a neighbour's junction
    sections enough for the loop to scale it too); the thickened mesh is then reinforced again under ``print_profile`` (its
    regions' settings follow the new shape). With nothing unfixable the mesh is not touched
    (``bone_scale`` all 1). ``before`` is the part as printed with ``print_profile``; ``after``
    the reinforced (and thickened) part, with each region's settings."""
    keys = ("force", "allowable_stress", "interval", "root", "build_direction",
            "layer_strength_ratio", "min_thickness", "junctions", "threads", "gap_tolerance")
    analysis_options = {k: correct_options[k] for k in keys if k in correct_options}
    first = reinforce(vertices, faces, skeleton, weights, print_profile=print_profile,
                      max_perimeters=max_perimeters, margin=margin, **analysis_options)
    if not first.unfixable:
        nb = skeleton.num_bones
        x_axes = np.tile([1.0, 0.0, 0.0], (nb, 1))
        return Correction(
            bone_scale=np.ones(nb), bone_scale_x=np.ones(nb), bone_scale_z=np.ones(nb),
            bone_x_axis=x_axes, vertices=np.array(first.vertices, dtype=float), rounds=[],
            converged=True, unfixed_sections=[], max_displacement=0.0,
            volume_change_percent=0.0, before=first.before, after=first.after,
            reason="reinforced: every weak region holds with more walls or denser infill; "
                   "the shape is unchanged",
            reinforcement=first)
    thick = correct(vertices, faces, skeleton, weights, **correct_options)
    second = reinforce(thick.vertices, faces, skeleton, weights, print_profile=print_profile,
                       max_perimeters=max_perimeters, margin=margin, **analysis_options)
    reason = (f"reinforced; {len(first.unfixable)} section(s) that even solid cannot carry "
              f"thickened ({thick.reason})")
    return dataclasses.replace(thick, before=first.before, after=second.after,
                               converged=bool(thick.converged and not second.unfixable),
                               reason=reason, reinforcement=second)


_api._REINFORCE_FIRST[:] = [reinforce_then_correct]  # correct(..., reinforce_first=True)
