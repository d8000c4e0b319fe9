"""bpy-free logic of the osteon add-on: materials, units, colours, reports.

Nothing here imports ``bpy``: it is unit-tested with plain Python and shared by
the operators, the batch script and (later) the live mode.  Units: mm of the
printed object, N, MPa (= N/mm^2).
"""

from __future__ import annotations

import importlib
import os
import sys
from dataclasses import dataclass

import numpy as np

# --------------------------------------------------------------------------- materials


@dataclass(frozen=True)
class Material:
    key: str
    label: str
    strength_mpa: float
    note: str


# Typical tensile strengths of *printed* parts (datasheet values along the layers;
# across layers FDM parts are weaker, which is what the safety factor is for).
MATERIALS: tuple[Material, ...] = (
    Material("PLA", "PLA", 60.0, "FDM PLA, ~50-65 MPa along layers"),
    Material("PETG", "PETG", 50.0, "FDM PETG, ~45-55 MPa"),
    Material("ABS", "ABS", 40.0, "FDM ABS, ~35-45 MPa"),
    Material("RESIN", "Resin", 45.0, "standard SLA/DLP resin, ~40-65 MPa"),
    Material("NYLON", "Nylon (PA12)", 48.0, "SLS PA12, ~45-50 MPa"),
    Material("CUSTOM", "Custom", 60.0, "your own strength value"),
)
MATERIAL_BY_KEY = {m.key: m for m in MATERIALS}
DEFAULT_SAFETY_FACTOR = 2.0


def allowable_stress(strength_mpa: float, safety_factor: float) -> float:
    """Allowable stress [sigma] in MPa = material strength / safety factor."""
    if not (strength_mpa > 0.0):
        raise ValueError(f"material strength must be > 0 MPa, got {strength_mpa}")
    if not (safety_factor > 0.0):
        raise ValueError(f"safety factor must be > 0, got {safety_factor}")
    return float(strength_mpa) / float(safety_factor)


# --------------------------------------------------------------------------- units

SCALING_MODES = (
    ("THIN", "Thin direction", ("Flat parts are thickened across their thickness only (pose "
                                "scale X or Z); round parts on both axes. Keeps widths, adds "
                                "less material")),
    ("UNIFORM", "Both axes", ("Every weak part is thickened on both axes across the bone "
                              "(pose scale X and Z), as in the paper")),
)

SIZE_MODES = (
    ("HEIGHT", "Printed height", "The model's world Z extent becomes this many mm"),
    ("LARGEST", "Largest dimension", "The model's largest world extent becomes this many mm"),
    ("UNITS", "Scene units", "Use the scene unit scale: 1 Blender unit = scale_length metres"),
)


def mm_per_unit(mode: str, size_mm: float, extent: np.ndarray, unit_scale_length: float) -> float:
    """Millimetres of the printed object per world (Blender) unit.

    ``extent`` is the (3,) world-space bounding-box size of the model in Blender units.
    """
    extent = np.asarray(extent, dtype=np.float64)
    if mode == "UNITS":
        if not (unit_scale_length > 0.0):
            raise ValueError("scene unit scale must be > 0")
        return float(unit_scale_length) * 1000.0
    if not (size_mm > 0.0):
        raise ValueError(f"print size must be > 0 mm, got {size_mm}")
    ref = float(extent[2]) if mode == "HEIGHT" else float(extent.max())
    if not (ref > 0.0) or not np.isfinite(ref):
        what = "height (Z extent)" if mode == "HEIGHT" else "size"
        raise ValueError(f"the model has zero {what}; pick another print-size mode")
    return float(size_mm) / ref


# --------------------------------------------------------------------------- colours

GREY = (0.45, 0.45, 0.45, 1.0)
# blue -> cyan -> green -> yellow -> red, stops at 0, .25, .5, .75, 1 x allowable
_RAMP = np.array(
    [
        [0.00, 0.05, 1.00],
        [0.00, 0.80, 1.00],
        [0.05, 0.85, 0.10],
        [1.00, 0.85, 0.00],
        [1.00, 0.00, 0.00],
    ],
    dtype=np.float32,
)


_STOPS = np.linspace(0.0, 1.0, len(_RAMP))


def ramp(t: np.ndarray) -> np.ndarray:
    """Colour ramp for t in [0, 1] (clipped; NaN -> 0) -> (N, 3) float32 RGB."""
    t = np.asarray(t, dtype=np.float64).ravel()
    t = np.where(np.isnan(t), 0.0, t)
    out = np.empty((t.shape[0], 3), dtype=np.float32)
    for c in range(3):
        out[:, c] = np.interp(t, _STOPS, _RAMP[:, c])  # clips outside [0, 1]
    return out


_LUT_SIZE = 2048
# RGBA lookup table: rows 0.._LUT_SIZE-1 the ramp over [0, allowable], the last row grey
_LUT = np.ones((_LUT_SIZE + 1, 4), dtype=np.float32)
_LUT[:_LUT_SIZE, :3] = ramp(np.linspace(0.0, 1.0, _LUT_SIZE))
_LUT[_LUT_SIZE] = GREY


def stress_colors(vertex_stress: np.ndarray, allowable_mpa: float,
                  vertex_culled: np.ndarray | None = None) -> np.ndarray:
    """Per-vertex RGBA (V, 4) float32: blue at 0 MPa -> red at the allowable stress
    (and above), grey where the vertex lies on culled (surely safe) sections.
    One table lookup per vertex (the ramp in 2048 steps): ~1 ms for 100k vertices."""
    s = np.asarray(vertex_stress, dtype=np.float64)
    t = s * ((_LUT_SIZE - 1) / float(allowable_mpa))
    np.clip(t, 0.0, _LUT_SIZE - 1, out=t)  # NaN stays NaN ...
    idx = np.nan_to_num(t, nan=0.0).astype(np.intp)  # ... and becomes 0 MPa (blue)
    if vertex_culled is not None:
        idx[np.asarray(vertex_culled, dtype=bool)] = _LUT_SIZE
    return np.take(_LUT, idx, axis=0)


# --------------------------------------------------------------------------- engine


class OsteonError(Exception):
    """A user-facing problem: its message is shown by report() / printed by batch."""


_VENDOR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "_vendor")


def import_engine():
    """Import the ``osteon`` engine; the legacy zip bundles it in ``_vendor/``."""
    error: ImportError | None = None
    for attempt in range(2):
        if attempt == 1:
            if not os.path.isdir(_VENDOR) or _VENDOR in sys.path:
                break
            sys.path.insert(0, _VENDOR)
        try:
            return importlib.import_module("osteon")
        except ImportError as e:
            error = e
    raise OsteonError(
        "the osteon engine is not importable in this Blender "
        f"(Python {sys.version_info.major}.{sys.version_info.minor}): {error}. "
        "Install the extension zip (Blender 4.2+) or see docs/blender.md"
    ) from error


# --------------------------------------------------------------------------- results


@dataclass
class BoneResult:
    index: int
    name: str
    max_stress_mpa: float
    ratio: float
    weak: bool
    scale: float


def bone_results(section_bone: np.ndarray, stress: np.ndarray, weak: np.ndarray,
                 bone_names: list[str], allowable_mpa: float,
                 bone_scale: np.ndarray | None = None) -> list[BoneResult]:
    """One row per bone that has sections, sorted by stress ratio, highest first."""
    section_bone = np.asarray(section_bone, dtype=np.int64)
    stress = np.asarray(stress, dtype=np.float64)
    weak = np.asarray(weak, dtype=bool)
    nb = len(bone_names)
    finite = np.where(np.isfinite(stress), stress, 0.0)
    mx = np.full(nb, -np.inf)
    np.maximum.at(mx, section_bone, finite)
    anyweak = np.zeros(nb, dtype=bool)
    np.logical_or.at(anyweak, section_bone, weak)
    rows = []
    for b in np.flatnonzero(np.isfinite(mx)):
        sc = float(bone_scale[b]) if bone_scale is not None else 1.0
        rows.append(BoneResult(int(b), bone_names[b], float(mx[b]), float(mx[b] / allowable_mpa),
                               bool(anyweak[b]), sc))
    rows.sort(key=lambda r: -r.ratio)
    return rows


def _finite(x) -> float:
    """JSON has no NaN/inf: non-finite numbers become 0.0."""
    x = float(x)
    return x if np.isfinite(x) else 0.0


def build_report(*, object_name: str, armature_name: str, bone_names: list[str],
                 analysis, allowable_mpa: float, settings: dict, mm_per_unit: float,
                 correction=None, corrected_analysis=None) -> dict:
    """The JSON report of SPEC section 8 (plus details).

    ``analysis`` is the ``osteon.Analysis`` of the model as it was; with a correction,
    ``corrected_analysis`` is the state after it (what ``max_stress_mpa`` etc. describe)
    and ``weak_bones`` lists every bone weak before or after, with its scale, its
    stress now (``max_stress_mpa``), before (``max_stress_before_mpa``) and ``weak`` now."""
    shown = corrected_analysis if corrected_analysis is not None else analysis
    scale = np.asarray(correction.bone_scale) if correction is not None else None
    rows = bone_results(shown.section_bone, shown.stress, shown.weak, bone_names,
                        allowable_mpa, scale)
    weak_rows = [r for r in rows if r.weak]
    weak_bones = [{"bone": r.name, "max_stress_mpa": r.max_stress_mpa, "ratio": r.ratio,
                   "scale": r.scale, "weak": True} for r in weak_rows]
    if correction is not None:
        before = {r.name: r for r in bone_results(analysis.section_bone, analysis.stress,
                                                  analysis.weak, bone_names, allowable_mpa)}
        weak_bones = [
            {"bone": r.name, "max_stress_mpa": r.max_stress_mpa, "ratio": r.ratio,
             "scale": r.scale, "weak": r.weak,
             "max_stress_before_mpa": before[r.name].max_stress_mpa if r.name in before else 0.0}
            for r in rows if r.weak or (r.name in before and before[r.name].weak)
        ]
    report = {
        "object": object_name,
        "armature": armature_name,
        "units": {"length": "mm", "force": "N", "stress": "MPa"},
        "settings": settings,
        "mm_per_blender_unit": float(mm_per_unit),
        "max_stress_mpa": _finite(shown.max_stress),
        "allowable_stress_mpa": float(allowable_mpa),
        "stress_ratio": _finite(shown.max_stress) / float(allowable_mpa),
        "sections": len(shown.stress),
        "weak_sections": int(np.count_nonzero(shown.weak)),
        "culled_sections": int(np.count_nonzero(shown.culled)),
        "safe_modulus_mm3": _finite(shown.safe_modulus),
        "weak_bones": weak_bones,
        "bones": [
            {"bone": r.name, "max_stress_mpa": r.max_stress_mpa, "ratio": r.ratio,
             "weak": r.weak, "scale": r.scale}
            for r in rows
        ],
        "converged": bool(not weak_rows) if correction is None else bool(correction.converged),
        "corrected": correction is not None,
    }
    if correction is not None:
        rounds = correction.rounds
        report["correction"] = {
            "rounds": len(rounds) if hasattr(rounds, "__len__") else int(rounds),
            "reason": str(getattr(correction, "reason", "")),
            "converged": bool(correction.converged),
            "max_stress_before_mpa": _finite(analysis.max_stress),
            "max_stress_after_mpa": _finite(shown.max_stress),
            "engine_max_stress_after_mpa": _finite(correction.after.max_stress),
            "bone_scale": {bone_names[i]: float(s) for i, s in enumerate(scale) if s != 1.0},
        }
        sx, sz = getattr(correction, "bone_scale_x", None), getattr(correction, "bone_scale_z", None)
        if sx is not None and sz is not None:
            # pose scale X and Z of each scaled bone (they differ where a flat part was
            # thickened across its thickness only)
            report["correction"]["bone_scale_xz"] = {
                bone_names[i]: [float(sx[i]), float(sz[i])]
                for i in range(len(bone_names)) if sx[i] != 1.0 or sz[i] != 1.0}
    return report
