"""bpy-free logic of the osteon add-on that is Blender's own: size modes, the colour
ramp, importing the engine.  Materials, the allowable stress and the report come from
the wheel (``osteon.materials``, ``osteon.report``, ``osteon.settings``).

Nothing here imports ``bpy``: it is unit-tested with plain Python and shared by
the operators, the batch script and the live mode.  Units: mm of the
printed object, N, MPa (= N/mm^2).
"""

from __future__ import annotations

import importlib
import os
import sys

import numpy as np

from .errors import OsteonError

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
# vertices of bones that were not analysed (too many sections skipped): never a stress colour
MAGENTA = (1.0, 0.0, 1.0, 1.0)
RED = (1.0, 0.0, 0.0, 1.0)
DOUBT_LEGEND = "bone not analysed, its sections could not be cut"
# below the limit, by stress / allowable: blue -> cyan -> green -> yellow -> orange at stops
# 0, .25, .5, .75, 1 (orange: just below the limit); red only over it (ratio >= 1), so that a
# part within the limit never looks broken
_RAMP = np.array(
    [
        [0.00, 0.05, 1.00],
        [0.00, 0.80, 1.00],
        [0.05, 0.85, 0.10],
        [1.00, 0.85, 0.00],
        [1.00, 0.45, 0.00],
    ],
    dtype=np.float32,
)
#: the colour scale in words, for the legend (ui/panel.py, docs/blender.md): (RGBA, the
#: Blender icon nearest that colour, text); numbers are stress / allowable (σ/[σ])
LEGEND = (
    ((0.00, 0.05, 1.00, 1.0), "COLLECTION_COLOR_05", "0: unloaded"),
    ((0.05, 0.85, 0.10, 1.0), "COLLECTION_COLOR_04", "0.5: half the limit"),
    ((1.00, 0.45, 0.00, 1.0), "COLLECTION_COLOR_02", "just below 1: within the limit"),
    (RED, "COLLECTION_COLOR_01", "1 and over: over the limit"),
    (GREY, "OUTLINER_COLLECTION", "grey: surely safe, far below the limit (not cut)"),
    (MAGENTA, "COLLECTION_COLOR_06", "magenta: not analysed, could not be cut"),
)


_STOPS = np.linspace(0.0, 1.0, len(_RAMP))


def ramp(t: np.ndarray) -> np.ndarray:
    """Colour for stress / allowable ``t`` (NaN -> 0) -> (N, 3) float32 RGB: the ramp over
    [0, 1), red at 1 and above."""
    t = np.asarray(t, dtype=np.float64).ravel()
    t = np.where(np.isnan(t), 0.0, t)
    out = np.empty((t.shape[0], 3), dtype=np.float32)
    for c in range(3):
        out[:, c] = np.interp(t, _STOPS, _RAMP[:, c])  # clips outside [0, 1]
    out[t >= 1.0] = RED[:3]
    return out


_LUT_SIZE = 2048
# RGBA lookup table: rows 0.._LUT_SIZE-1 the ramp over [0, allowable), then red (at or over
# the allowable), then grey
_LUT = np.ones((_LUT_SIZE + 2, 4), dtype=np.float32)
_LUT[:_LUT_SIZE, :3] = ramp(np.linspace(0.0, 1.0, _LUT_SIZE, endpoint=False))
_LUT[_LUT_SIZE] = RED
_LUT[_LUT_SIZE + 1] = GREY
# the same table, one 16-byte item per row: a flat gather (faster than take(axis=0) of rows)
_LUT_ROWS = _LUT.view(np.complex128).ravel()


def stress_colors(vertex_stress: np.ndarray, allowable_mpa: float,
                  vertex_culled: np.ndarray | None = None,
                  vertex_doubt: np.ndarray | None = None) -> np.ndarray:
    """Per-vertex RGBA (V, 4) float32: blue at 0 MPa -> orange just below the allowable
    stress, red at and above it, grey where the vertex lies on culled (surely safe) sections,
    magenta where ``vertex_doubt`` (V,) bool is set (its bone was not analysed:
    DOUBT_LEGEND). One table lookup per vertex (the ramp in 2048 steps): ~1 ms for 100k
    vertices."""
    s = np.asarray(vertex_stress, dtype=np.float64)
    t = s * (_LUT_SIZE / float(allowable_mpa))
    np.fmax(t, 0.0, out=t)      # NaN -> 0 MPa (blue: fmax takes the number), below 0 -> 0
    np.fmin(t, _LUT_SIZE, out=t)
    idx = t.astype(np.intp)
    if vertex_culled is not None:
        idx[np.asarray(vertex_culled, dtype=bool)] = _LUT_SIZE + 1
    out = np.take(_LUT_ROWS, idx).view(np.float32).reshape(-1, 4)
    if vertex_doubt is not None:
        out[np.asarray(vertex_doubt, dtype=bool)] = MAGENTA
    return out


def result_colors(analysis, heads_mm: np.ndarray, tails_mm: np.ndarray,
                  vertex_doubt: np.ndarray | None = None) -> np.ndarray:
    """The stress layer of a result, the same for Analyze, Correct and Live: per vertex the
    stress ratio at the print direction (``printdir.colour_stress``: stress / the allowable at
    its bone's angle to the layers) on :func:`stress_colors`' scale."""
    shown = printdir.colour_stress(analysis, heads_mm, tails_mm)
    return stress_colors(shown, float(analysis.allowable_stress),
                         getattr(analysis, "vertex_culled", None), vertex_doubt)


# --------------------------------------------------------------------------- engine


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


PYGEL3D_MISSING = (
    "Make skeleton needs the Python package 'pygel3d', which this Blender cannot import ({why}). "
    "The osteon zips for Linux (x64, arm64), Windows x64 and macOS 11+ carry it: install the "
    "zip made for this computer. Otherwise, in Blender's Python Console (Scripting tab) run: "
    "import subprocess, sys; subprocess.check_call([sys.executable, '-m', 'pip', 'install', "
    "'--user', 'pygel3d']) and restart Blender")


def import_pygel3d():
    """Import ``pygel3d`` (osteon.auto_skeleton's curve skeleton): the extension installs its
    bundled wheel, the legacy zip carries it unpacked in ``_vendor/`` (scripts/build_addon.py);
    OsteonError telling a zip user what to do in Blender when neither is there."""
    error: ImportError | None = None
    for attempt in range(2):
        if attempt == 1:
            if not os.path.isdir(_VENDOR) or _VENDOR in sys.path:
                break
            sys.path.append(_VENDOR)   # after the user's own packages
        try:
            return importlib.import_module("pygel3d")
        except (ImportError, OSError) as e:   # OSError: its shared library does not load
            error = e if isinstance(e, ImportError) else ImportError(str(e))
    raise OsteonError(PYGEL3D_MISSING.format(why=error))


# --------------------------------------------------------------------------- the wheel's facts

# Materials, allowable stress, the per-bone table and the report schema are the wheel's
# (osteon.materials, osteon.report, osteon.settings): the CLI and batch runs use the same ones.
import_engine()
from osteon import materials, report
from osteon.settings import Settings, engine_arguments, min_thickness_mm  # noqa: F401 (service)

from . import printdir, printprofile  # after import_engine: they read osteon's modules

MATERIALS = materials.MATERIALS
MATERIAL_BY_KEY = {m.key: m for m in MATERIALS}
DEFAULT_SAFETY_FACTOR = materials.DEFAULT_SAFETY_FACTOR
allowable_stress = report.allowable_stress
loose_pieces_sentence = report.loose_pieces_sentence
#: the material enum: the presets, then "Custom" (your own strength)
MATERIAL_ITEMS = [(m.key, m.label, f"{m.note}; strength {m.strength_mpa:g} MPa ({m.strength_source})")
                  for m in MATERIALS]
MATERIAL_ITEMS.append((materials.CUSTOM, "Custom", "your own strength value"))


def build_report(*, object_name: str, armature_name: str, bone_names: list[str],
                 analysis, allowable_mpa: float, settings: dict, mm_per_unit: float,
                 correction=None, corrected_analysis=None, vertices=None, faces=None,
                 seconds=None, section_table: bool = True) -> dict:
    """:func:`osteon.report.build_report` for a Blender mesh object and its armature
    (``mm_per_unit``: mm of the print per Blender unit; ``section_table=False``: without the
    per-section rows, Live's per-update report)."""
    return report.build_report(
        analysis=analysis, bone_names=bone_names, allowable_mpa=allowable_mpa,
        settings=settings, front_end="blender", model=object_name, object_name=object_name,
        armature_name=armature_name, mm_per_unit=mm_per_unit, vertices=vertices, faces=faces,
        seconds=seconds, correction=correction, corrected_analysis=corrected_analysis,
        section_table=section_table)


def _preset_exact(s, ratio: float) -> float:
    """The preset's layer ratio itself when the (float32) property holds it, so that the CLI
    and the add-on pass the same double to the engine."""
    m = MATERIAL_BY_KEY.get(s.material)
    if m is not None and abs(ratio - m.layer_strength_ratio) <= 1e-6:
        return m.layer_strength_ratio
    return ratio


def settings_of(s, orientation: dict | None = None) -> Settings:
    """``scene.osteon`` as the wheel's :class:`osteon.settings.Settings` (the build direction
    from the "Print direction" setting, the layer ratio from "Layer strength", ``junctions``
    from "Junction cores", the print profile from "Print settings"); ``orientation``: the
    scene's "Find best orientation" result (``state.SceneState.orientation``), which Print
    direction "Best found" reads)."""
    return Settings(
        build_direction=printdir.build_direction(s, orientation),
        layer_strength_ratio=_preset_exact(s, float(getattr(s, "layer_strength_ratio", 1.0))),
        force_n=float(s.force_n), interval_mm=float(s.interval_mm), material=s.material,
        strength_mpa=float(s.strength_mpa), safety_factor=float(s.safety_factor),
        held_bone=s.held_bone or None, size_mode=s.size_mode,
        print_size_mm=float(s.print_size_mm), max_scale=float(s.max_scale),
        max_rounds=int(s.max_rounds), scaling=str(s.scaling),
        junctions=bool(getattr(s, "junction_cores", True)),
        **printprofile.settings_fields(s))  # "Print settings" (walls, skins, infill)


def engine_params(s, arm, bone_names, correct: bool = False,
                  orientation: dict | None = None, settings: Settings | None = None) -> dict:
    """The engine's keyword arguments from ``scene.osteon`` (checked once, in the wheel);
    ``orientation`` as in :func:`settings_of`; ``settings``: ``settings_of(s, orientation)``
    when the caller has it."""
    try:
        kw = engine_arguments(settings if settings is not None else settings_of(s, orientation),
                              bone_names, correct=correct)
    except ValueError as e:
        msg = str(e)
        if msg.startswith("Held bone"):
            msg = f"Held bone '{s.held_bone}' is not a deform bone of '{arm.name}'"
        raise OsteonError(msg) from e
    # the add-on's own guard decides (the "Section limit" preference asks first, and OK or
    # max_sections=0 runs it anyway), not the wheel's default budget for unattended runs
    kw["max_sections"] = 2**31 - 1
    return kw
