"""Layer strength and the best build direction of an FDM print (issue 18, docs/printing.md).

Turning the model does not change its sections, moments or stresses, only the angle θ between
each section normal n and the build direction d. With in-plane strength X and layer strength
Z = r·X the allowable is ``1/[σ](θ) = cos²θ/Z + sin²θ/X``, so a section's stress ratio is

    σ / [σ](θ) = (σ / X) · (1 + (1/r − 1) cos²θ),      cos θ = n·d

and the worst ratio of every candidate direction is one (S × D) NumPy expression. Units: mm, MPa.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = [
    "Orientation",
    "best_orientation",
    "fibonacci_directions",
    "layer_allowable",
    "rotation_to_z",
    "worst_ratios",
]

_Z = np.array([0.0, 0.0, 1.0])



def layer_allowable(in_plane: float, ratio: float, cos2: Any) -> np.ndarray:
    """Allowable normal stress, MPa, at cos²θ = ``cos2`` to the build direction (array-like):
    ``ratio·X / (cos²θ + (1 − cos²θ)·ratio)``; X exactly when ``ratio == 1``."""
    c2 = np.clip(np.asarray(cos2, float), 0.0, 1.0)
    if ratio == 1.0:
        return np.full_like(c2, float(in_plane))
    return ratio * in_plane / (c2 + (1.0 - c2) * ratio)


def _unit(v: Any, name: str) -> np.ndarray:
    a = np.asarray(v, dtype=float).reshape(-1)
    if a.shape != (3,) or not np.isfinite(a).all() or not np.linalg.norm(a) > 0:
        raise ValueError(f"{name} must be a finite non-zero 3-vector, got {v!r}")
    return a / np.linalg.norm(a)


def _ratio(value: Any) -> float:
    try:
        r = float(value)
    except (TypeError, ValueError):
        raise ValueError("layer_strength_ratio must be a number (layer / in-plane strength)") from None
    if not (r > 0 and math.isfinite(r)):
        raise ValueError(f"layer_strength_ratio must be a positive finite number, got {value!r}")
    return r


def fibonacci_directions(n: int, axis: Any = _Z, half_angle_deg: float = 180.0) -> np.ndarray:
    """(n,3) unit directions spread evenly (Fibonacci lattice, equal area) over the spherical cap
    of ``half_angle_deg`` around ``axis`` (180 = the whole sphere)."""
    n = int(n)
    if n < 1:
        raise ValueError(f"samples must be >= 1, got {n}")
    cos_a = math.cos(math.radians(min(max(float(half_angle_deg), 0.0), 180.0)))
    i = np.arange(n) + 0.5
    z = 1.0 - (1.0 - cos_a) * i / n
    rho = np.sqrt(np.clip(1.0 - z * z, 0.0, None))
    phi = i * math.pi * (3.0 - math.sqrt(5.0))
    d = np.column_stack([rho * np.cos(phi), rho * np.sin(phi), z])
    a = _unit(axis, "axis")
    return d @ rotation_to_z(a)  # rows of R map a -> z; R.T maps z -> a


def rotation_to_z(direction: Any) -> np.ndarray:
    """(3,3) proper rotation R with ``R @ direction = (0, 0, 1)``: the smallest turn (about
    direction × z); a half turn about x when direction is −z. Rotate a model by ``V @ R.T``."""
    d = _unit(direction, "direction")
    c = float(d @ _Z)
    if c < -1.0 + 1e-12:
        return np.diag([1.0, -1.0, -1.0])
    v = np.cross(d, _Z)
    k = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + k + k @ k / (1.0 + c)


def _section_terms(analysis) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(valid section indices, their normals (S,3), stress / in-plane allowable (S,))."""
    stress = np.asarray(analysis.stress, float)
    ok = np.flatnonzero(np.isfinite(stress))
    n = np.asarray(analysis.section_normal, float)[ok]
    n = n / np.linalg.norm(n, axis=1, keepdims=True)
    return ok, n, stress[ok] / float(analysis.allowable_stress)


def worst_ratios(analysis, directions: Any, layer_strength_ratio: float | None = None,
                 *, block: int = 1 << 20) -> tuple[np.ndarray, np.ndarray]:
    """Worst stress ratio of the model printed along each of ``directions`` (D,3) and the
    section where it occurs: ((D,) ratios, (D,) section indices into ``analysis``).
    ``layer_strength_ratio`` defaults to the analysis's own (1.0 = isotropic)."""
    r = _ratio(_default_ratio(analysis) if layer_strength_ratio is None else layer_strength_ratio)
    return _worst(_section_terms(analysis), directions, r, block)


def _worst(terms, directions, r: float, block: int = 1 << 20):
    ok, n, a = terms
    d = np.asarray(directions, float).reshape(-1, 3)
    d = d / np.linalg.norm(d, axis=1, keepdims=True)
    if len(ok) == 0:
        return np.full(len(d), np.nan), np.full(len(d), -1)
    k = 1.0 / r - 1.0
    out = np.empty(len(d))
    arg = np.empty(len(d), dtype=np.int64)
    step = max(1, block // len(ok))
    for s in range(0, len(d), step):
        c = n @ d[s:s + step].T  # (S, b) cos θ
        np.multiply(c, c, out=c)
        c *= k
        c += 1.0
        c *= a[:, None]
        j = c.argmax(0)
        arg[s:s + step] = j
        out[s:s + step] = c[j, np.arange(c.shape[1])]
    return out, ok[arg]


def _default_ratio(analysis) -> float:
    return float(getattr(analysis, "layer_strength_ratio", 1.0))


@dataclass
class Orientation:
    """Result of :func:`best_orientation`.

    ``direction`` (3,) unit build direction in the model's frame; ``rotation`` (3,3) maps it to
    +Z (rotate the model by ``vertices @ rotation.T``, see :meth:`rotate`); ``worst_ratio`` the
    largest section stress / allowable there, ``worst_section`` its index; ``reference_ratio``
    the same at ``reference_direction`` (the analysis's build direction, default +Z);
    ``directions`` (D,3) and ``ratios`` (D,) the sphere map; ``candidates`` the best few
    distinct directions, best first, as dicts ``{direction, rotation, worst_ratio,
    worst_section, across_layers}`` (plus ``base_area_mm2`` with a flat base).
    """

    direction: np.ndarray
    rotation: np.ndarray
    worst_ratio: float
    worst_section: int
    reference_direction: np.ndarray
    reference_ratio: float
    layer_strength_ratio: float
    directions: np.ndarray
    ratios: np.ndarray
    candidates: list = field(default_factory=list)
    base: str | None = None

    @property
    def improvement(self) -> float:
        """reference_ratio / worst_ratio (> 1: the best direction is stronger)."""
        return float(self.reference_ratio / self.worst_ratio)

    def rotate(self, vertices: Any) -> np.ndarray:
        """(V,3) vertices turned so that the best direction points up (+Z), mm."""
        return np.asarray(vertices, float) @ self.rotation.T

    def __repr__(self) -> str:
        d = ", ".join(f"{x:+.3f}" for x in self.direction)
        return (f"Orientation(direction=({d}), worst_ratio={self.worst_ratio:.3f}, "
                f"reference {self.reference_ratio:.3f}, {len(self.ratios)} directions)")


def _across(analysis, section: int, direction: np.ndarray, r: float) -> bool:
    n = np.asarray(analysis.section_normal[section], float)
    c2 = float((n @ direction) ** 2 / (n @ n))
    return bool(r < 1.0 and c2 > r * (1.0 - c2))


def _refine(terms, r, seeds, values, step, allowed, min_step=1e-4, max_iter=80):
    """Pattern search on the sphere from every seed at once (K,3): try 8 directions at angle
    ``step`` around each, move to the best where it improves, else halve that seed's step."""
    d = np.array(seeds, float)
    f = np.array(values, float)
    h = np.full(len(d), float(step))
    ang = np.arange(8) * (math.pi / 4)
    ca, sa = np.cos(ang), np.sin(ang)
    for _ in range(max_iter):
        live = np.flatnonzero(h > min_step)
        if len(live) == 0:
            break
        dl = d[live]
        helper = np.where((np.abs(dl[:, 2]) < 0.9)[:, None], _Z, np.array([1.0, 0.0, 0.0]))
        u = np.cross(dl, helper)
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        v = np.cross(dl, u)
        ch, sh = np.cos(h[live])[:, None, None], np.sin(h[live])[:, None, None]
        cand = ch * dl[:, None, :] + sh * (ca[None, :, None] * u[:, None, :]
                                           + sa[None, :, None] * v[:, None, :])  # (L, 8, 3)
        cand = cand.reshape(-1, 3)
        vals, _ = _worst(terms, cand, r)
        vals = np.where(allowed(cand), vals, np.inf).reshape(len(live), 8)
        j = vals.argmin(1)
        best = vals[np.arange(len(live)), j]
        better = best < f[live] * (1.0 - 1e-9)
        moved = live[better]
        d[moved] = cand.reshape(len(live), 8, 3)[better, j[better]]
        d[moved] /= np.linalg.norm(d[moved], axis=1, keepdims=True)
        f[moved] = best[better]
        h[live[~better]] *= 0.5
    return d, f


def _printed(print_profile) -> bool:
    if print_profile is None:
        return False
    from .profiles import get_profile

    return not get_profile(print_profile).is_solid


def _model_parts(model):
    if model is None:
        raise ValueError("best_orientation with a print profile needs model=(vertices, faces, "
                         "skeleton, weights): each candidate is analysed again")
    if isinstance(model, (tuple, list)):
        if len(model) != 4:
            raise ValueError("model must be (vertices, faces, skeleton, weights)")
        return tuple(model)
    return model.vertices, model.faces, model.skeleton, model.weights


def _rescore_printed(analysis, cands, ref, r, print_profile, model, rescore, engine_options,
                     symmetric, allowed):
    """The candidates re-ranked by the worst stress ratio of the printed part analysed at each
    direction (see :func:`best_orientation`); each gets ``search_ratio`` (the sphere search's:
    ``analysis``'s own sections turned there, solid when ``analysis`` was)
    and ``worst_ratio`` / ``worst_section`` of its own printed analysis."""
    from ._api import analyze
    from .profiles import get_profile

    profile = get_profile(print_profile)
    vertices, faces, skeleton, weights = _model_parts(model)
    same = math.cos(math.radians(2.0))  # directions closer than 2° are analysed once

    def new(d, dirs):
        return not any((abs(float(d @ e)) if symmetric else float(d @ e)) > same for e in dirs)

    dirs: list = []
    for c in cands:  # the sphere search's best distinct directions
        if len(dirs) < max(0, int(rescore)) and not np.array_equal(c["direction"], ref) \
                and new(c["direction"], dirs):
            dirs.append(c["direction"])
    for d in (ref, *np.eye(3)):  # the current direction (first) and the axes
        if allowed(np.asarray(d)[None])[0] and (d is ref or new(d, dirs)):
            dirs.append(np.asarray(d, float))
    kw = {"force": analysis.force, "allowable_stress": analysis.allowable_stress,
          "interval": analysis.interval, "root": int(analysis.held_bone),
          "layer_strength_ratio": r, "min_thickness": analysis.min_thickness,
          **(engine_options or {})}
    out = []
    for d in dirs:
        a = analyze(vertices, faces, skeleton, weights, build_direction=d,
                    print_profile=profile, **kw)
        f, w = _worst(_section_terms(a), d[None], r)
        search = float(_worst(_section_terms(analysis), d[None], r)[0][0])
        out.append({"direction": d, "rotation": rotation_to_z(d), "worst_ratio": float(f[0]),
                    "worst_section": int(w[0]), "search_ratio": search,
                    "across_layers": _across(a, int(w[0]), d, r) if w[0] >= 0 else False})
    lo = min(c["worst_ratio"] for c in out)

    def key(c):  # ties (1e-6) keep the smaller turn from the current direction
        dot = abs(float(c["direction"] @ ref)) if symmetric else float(c["direction"] @ ref)
        return (0, math.acos(min(1.0, dot))) if c["worst_ratio"] <= lo * (1 + 1e-6) \
            else (1, c["worst_ratio"])

    out.sort(key=key)
    return out


def _hull_bases(vertices: Any) -> tuple[np.ndarray, np.ndarray]:
    """Outward unit normals (K,3) of the convex hull's flat faces (coplanar facets merged) and
    their areas (K,) mm²."""
    from scipy.spatial import ConvexHull

    v = np.asarray(vertices, float)
    if v.ndim != 2 or v.shape[1] != 3 or len(v) < 4 or not np.isfinite(v).all():
        raise ValueError("base='flat' needs vertices (V,3) with V >= 4 finite points, mm")
    hull = ConvexHull(v)
    normals = hull.equations[:, :3]
    tri = v[hull.simplices]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    key = np.round(normals * 1e6).astype(np.int64)
    uniq, inv = np.unique(key, axis=0, return_inverse=True)
    inv = inv.ravel()
    tot = np.bincount(inv, weights=area, minlength=len(uniq))
    nrm = np.zeros((len(uniq), 3))
    np.add.at(nrm, inv, normals * area[:, None])
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    return nrm, tot


def best_orientation(
    analysis,
    *,
    samples: int = 4000,
    layer_strength_ratio: float | None = None,
    base: str | None = None,
    vertices: Any = None,
    cone: tuple | None = None,
    top: int = 5,
    min_base_area: float = 0.0,
    print_profile=None,
    model: Any = None,
    rescore: int = 6,
    engine_options: dict | None = None,
) -> Orientation:
    """The build direction that minimises the worst section stress ratio of ``analysis``.

    ``samples`` directions on a Fibonacci sphere (or on the allowed cone) are evaluated at once,
    then the best few are refined locally. ``layer_strength_ratio`` Z/X (default: the analysis's
    own; 1.0 = isotropic, every direction equal: +Z is returned). ``base="flat"`` allows only
    resting the part on a face of its convex hull (``vertices`` (V,3) mm required; the build
    direction is minus that face's outward normal; faces smaller than ``min_base_area`` mm² are
    skipped). ``cone=(axis (3,), half_angle_deg)`` allows only directions within that angle of
    ``axis``. A direction d and −d give the same ratios; unconstrained results prefer the one
    nearer +Z (the smaller turn). Returns an :class:`Orientation`.

    ``print_profile`` (an :class:`osteon.profiles.PrintProfile` or a preset key; default solid):
    a printed section changes with the build direction (a section across the layers has skins
    above and below, one in the layer plane perimeters all round; docs/printing.md), which the
    sphere search above cannot see: it turns only the allowable. So with a profile that is not
    solid the ``rescore`` best distinct directions of that search, the current direction and
    the three axes (±X, ±Y, ±Z: where an isotropic material leaves every direction tied) are
    analysed again with the profile at their own build direction, and the lowest worst ratio
    of those analyses wins. That needs ``model``: (vertices, faces, skeleton, weights) or an
    object with those attributes (e.g. ``osteon.io.RiggedModel``); ``engine_options`` extra
    keywords of :func:`osteon.analyze` (e.g. ``junctions``). Cost: up to ``rescore`` + 4
    analyses (docs/printing.md, "Orientation with a print profile").
    """
    r = _ratio(_default_ratio(analysis) if layer_strength_ratio is None else layer_strength_ratio)
    samples = int(samples)
    if samples < 1:
        raise ValueError(f"samples must be >= 1, got {samples}")
    if base not in (None, "flat"):
        raise ValueError(f"base must be None or 'flat', got {base!r}")
    top = max(1, int(top))
    ref = np.asarray(getattr(analysis, "build_direction", _Z), float)
    ref = ref / np.linalg.norm(ref)
    terms = _section_terms(analysis)
    ref_ratio = float(_worst(terms, ref[None], r)[0][0])

    cone_axis, cos_cone, half = None, -1.0, 180.0
    if cone is not None:
        try:
            axis, half = cone
        except (TypeError, ValueError):
            raise ValueError("cone must be (axis (3,), half_angle_deg)") from None
        cone_axis = _unit(axis, "cone axis")
        half = float(half)
        if not (0.0 < half <= 180.0):
            raise ValueError(f"cone half angle must be in (0, 180] degrees, got {half!r}")
        cos_cone = math.cos(math.radians(half))

    def allowed(d):
        if cone_axis is None:
            return np.ones(len(d), bool)
        return d @ cone_axis >= cos_cone - 1e-12

    areas = None
    if base == "flat":
        if vertices is None:
            raise ValueError("base='flat' needs the model's vertices (V,3), mm")
        normals, areas = _hull_bases(vertices)
        keep = areas >= float(min_base_area)
        dirs = -normals[keep]
        areas = areas[keep]
        ok = allowed(dirs)
        dirs, areas = dirs[ok], areas[ok]
        if len(dirs) == 0:
            raise ValueError("no convex-hull face satisfies the constraints (cone, min_base_area)")
    elif cone_axis is not None:
        dirs = fibonacci_directions(samples, cone_axis, half)
    else:
        dirs = fibonacci_directions(samples)
    ratios, _ = _worst(terms, dirs, r)

    # The best few distinct seeds (d ~ -d when unconstrained), then local refinement.
    order = np.argsort(ratios, kind="stable")
    symmetric = base is None and cone_axis is None
    spacing = math.sqrt(4.0 * math.pi / max(samples, 1)) if cone_axis is None else math.sqrt(
        2.0 * math.pi * (1.0 - cos_cone) / max(samples, 1))
    sep = max(3.0 * spacing, math.radians(5.0))
    picked: list[int] = []
    for i in order:
        d = dirs[i]
        if any(abs(float(d @ dirs[j])) > math.cos(sep) if symmetric
               else float(d @ dirs[j]) > math.cos(sep) for j in picked):
            continue
        picked.append(int(i))
        if len(picked) >= max(top, 4):
            break
    seeds, seed_vals = dirs[picked], ratios[picked]
    if base is None and r != 1.0:
        if allowed(ref[None])[0]:  # also descend from the current direction: the nearest optimum
            picked.append(-1)
            seeds = np.vstack([seeds, ref])
            seed_vals = np.append(seed_vals, ref_ratio)
        seeds, seed_vals = _refine(terms, r, seeds, seed_vals, spacing, allowed)
    cands = []
    for i, d in zip(picked, seeds, strict=True):
        if symmetric and d[2] < 0:
            d = -d
        f_arr, w_arr = _worst(terms, d[None], r)
        c = {"direction": d, "rotation": rotation_to_z(d), "worst_ratio": float(f_arr[0]),
             "worst_section": int(w_arr[0]),
             "across_layers": _across(analysis, int(w_arr[0]), d, r) if w_arr[0] >= 0 else False}
        if areas is not None:
            c["base_area_mm2"] = float(areas[i])
        cands.append(c)
    if base is None and allowed(ref[None])[0]:
        # The current direction competes too (ties keep the model as it is; isotropic material
        # makes every direction equal).
        cands.insert(0, {"direction": ref, "rotation": rotation_to_z(ref),
                         "worst_ratio": ref_ratio,
                         "worst_section": int(_worst(terms, ref[None], r)[1][0]),
                         "across_layers": False})
    # Best ratio first; ratios equal to 1e-6 (a plateau of the worst section) prefer the
    # smaller turn from the current direction.
    lo = min(c["worst_ratio"] for c in cands)

    def key(c):
        turn = math.acos(min(1.0, abs(float(c["direction"] @ ref)) if symmetric
                             else float(c["direction"] @ ref)))
        tied = c["worst_ratio"] <= lo * (1.0 + 1e-6)
        return (0, turn) if tied else (1, c["worst_ratio"])

    cands.sort(key=key)
    if _printed(print_profile):
        cands = _rescore_printed(analysis, cands, ref, r, print_profile, model, rescore,
                                 engine_options, symmetric, allowed)
    cands_all = cands
    cands = cands[:top]
    best = cands[0]
    if _printed(print_profile):  # the current direction's printed ratio (it was analysed)
        ref_ratio = next((c["worst_ratio"] for c in cands_all if
                          np.array_equal(c["direction"], ref)), ref_ratio)
    return Orientation(
        direction=best["direction"], rotation=best["rotation"], worst_ratio=best["worst_ratio"],
        worst_section=best["worst_section"], reference_direction=ref, reference_ratio=ref_ratio,
        layer_strength_ratio=r, directions=dirs, ratios=ratios, candidates=cands, base=base,
    )
