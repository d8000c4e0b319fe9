"""The settings of one analysis, checked once: :class:`AnalysisOptions`.

:func:`osteon.analyze`, :class:`osteon.Analyzer` and :func:`osteon.correct` take these settings
as keywords (``force=...``) or as ``options=AnalysisOptions(...)``; either way they become one
:class:`AnalysisOptions`, whose constructor is the only place their values are checked
(``ValueError`` naming the setting), and :func:`engine_options` is the only place they become
the engine's ``_core.AnalysisOptions``. Units: mm, N, MPa.

Adding an option (docs/architecture.md): one :func:`_option` field below (default, unit, doc,
check) and, for an engine setting, one line in :func:`engine_options` (plus the C++
``AnalysisOptions`` member and its ``def_readwrite`` in bindings/python/core.cpp).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from . import _core
from .printed import engine_print_options
from .profiles import PrintProfile, get_profile

__all__ = ["DEFAULT_MIN_THICKNESS", "MAX_SECTIONS", "AnalysisOptions", "engine_options",
           "section_budget"]

#: Default minimum printable thickness, mm (FDM: two perimeters of a 0.4 mm nozzle).
DEFAULT_MIN_THICKNESS = 0.8


def _positive(value: float, name: str, unit: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number ({unit})") from None
    if not (v > 0 and math.isfinite(v)):
        raise ValueError(f"{name} must be a positive finite number ({unit}), got {value!r}")
    return v


def _build_direction(value: Any) -> tuple[float, float, float]:
    """The unit build direction of a finite non-zero 3-vector."""
    try:
        d = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ValueError(f"build_direction must be a 3-vector, got {value!r}") from None
    if d.shape != (3,) or not np.isfinite(d).all() or not np.linalg.norm(d) > 0:
        raise ValueError(f"build_direction must be a finite non-zero 3-vector, got {value!r}")
    return tuple(float(x) for x in d / np.linalg.norm(d))


def _layer_strength_ratio(value: Any) -> float:
    try:
        r = float(value)
    except (TypeError, ValueError):
        raise ValueError("layer_strength_ratio must be a number (layer / in-plane strength)"
                         ) from None
    if not (r > 0 and math.isfinite(r)):
        raise ValueError(f"layer_strength_ratio must be a positive finite number, got {value!r}")
    return r


def _layer_options(build_direction: Any, layer_strength_ratio: Any) -> tuple[np.ndarray, float]:
    """(unit build direction (3,), layer strength ratio) checked; ValueError naming the problem."""
    return np.array(_build_direction(build_direction)), _layer_strength_ratio(layer_strength_ratio)


def _min_thickness(value: Any) -> float:
    """``min_thickness`` in mm: None -> the default; must be a finite number >= 0."""
    if value is None:
        return DEFAULT_MIN_THICKNESS
    try:
        t = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"min_thickness must be a number of mm, got {value!r}") from None
    if not (t >= 0.0 and math.isfinite(t)):
        raise ValueError(f"min_thickness must be a finite length >= 0 mm, got {value!r}")
    return t


def _switch(value: Any, name: str) -> bool:
    """A yes/no argument: True/False (a NumPy bool, or 1/0); ``ValueError`` naming it otherwise
    (a string such as "false" is not taken for True)."""
    if isinstance(value, (bool, np.bool_)) or (isinstance(value, (int, np.integer))
                                                and value in (0, 1)):
        return bool(value)
    raise ValueError(f"{name} must be True or False, got {value!r}")


def _count(value: Any, name: str) -> int:
    """A non-negative integer setting (threads, max_rounds) that fits the engine's int."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name} must be an integer >= 0, got {value!r}")  # noqa: TRY004
    if not 0 <= int(value) <= 2**31 - 1:
        raise ValueError(f"{name} must be an integer >= 0 (at most 2^31 - 1), got {value!r}")
    return int(value)


def _root(value: Any) -> int | str | None:
    """A bone index or name (resolved against the skeleton by :func:`engine_options`)."""
    if value is None:
        return None
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer, str)):
        raise ValueError(f"root must be a bone index or name, got {value!r}")  # noqa: TRY004
    return value if isinstance(value, str) else int(value)


def _gap_tolerance(value: Any) -> float | None:
    if value is not None and not (float(value) >= 0):
        raise ValueError("gap_tolerance must be >= 0 mm")
    return None if value is None else float(value)


def _notch_sensitivity(value: Any) -> float:
    """``notch_sensitivity`` q: None -> 1 (the safe side); must be a number from 0 to 1."""
    if value is None:
        return 1.0
    try:
        q = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"notch_sensitivity must be a number from 0 to 1, got {value!r}"
                         ) from None
    if not 0.0 <= q <= 1.0:
        raise ValueError(f"notch_sensitivity must be a number from 0 to 1, got {value!r}")
    return q


def _min_notch_radius(value: Any) -> float:
    """``min_notch_radius`` mm: None -> 0.2 (half a 0.4 mm nozzle's line); positive, finite."""
    return 0.2 if value is None else _positive(value, "min_notch_radius", "mm")


#: Sections above which an analysis is refused before any work (``max_sections``; the CLI's and
#: batch's ``--max-sections``, raised by the user): the whole model, not per bone. ~11 kB of
#: memory per section was measured (616 659 sections took 6.9 GB), so 200 000 is about 2 GB.
MAX_SECTIONS = 200_000
#: memory per section (bytes): 6.9 GB / 616 659 sections on a model read 1000x too big
#: (issue 36); a 2-bone bar of 10 001 and 30 001 sections peaked at 10.5 kB per section
#: (readers branch, resource.getrusage)
BYTES_PER_SECTION = 11_200


def section_budget(sections: int, vertices: int, interval_mm: float, model_size_mm: float,
                   limit: int = MAX_SECTIONS, setting: str = "--max-sections") -> str | None:
    """``None`` when the whole model's ``sections`` (:func:`osteon.estimate_sections`) are
    within ``limit``, else the reason to refuse it, with the estimate of sections and memory:
    "616 659 sections (~6.9 GB) at 2 mm on a 120 m model: above the limit of 200 000 (check the
    print size, or raise --max-sections)". ``vertices``: the mesh's vertex count (mm);
    ``setting``: the name the caller raises the limit by (the CLI's option, the API's
    ``max_sections``)."""
    if int(sections) <= int(limit):
        return None
    gb = (int(sections) * BYTES_PER_SECTION + int(vertices) * 200) / 1e9

    def grouped(n: int) -> str:
        return f"{int(n):,}".replace(",", " ")

    return (f"{grouped(sections)} sections (~{gb:.1f} GB of memory) at {float(interval_mm):g} "
            f"mm on a {_length_text(float(model_size_mm))} model: above the limit of "
            f"{grouped(limit)} sections (check the print size, or raise {setting})")


def _length_text(mm: float) -> str:
    """A length for a message: "120 mm", "2.45 m", "2.35 km"."""
    if mm >= 1e6:
        return f"{mm / 1e6:.3g} km"
    if mm >= 1e3:
        return f"{mm / 1e3:.3g} m"
    return f"{mm:.3g} mm"


def _max_sections(value: Any) -> int:
    """``max_sections``: an integer >= 1 (the whole model's section budget)."""
    n = _count(value, "max_sections")
    if n < 1:
        raise ValueError(f"max_sections must be an integer >= 1, got {value!r}")
    return n


def _option(default: Any, unit: str, doc: str, check=None):
    """A field of :class:`AnalysisOptions`: its default, unit, one-line doc and the function
    that checks and normalises a value (``ValueError`` naming the setting)."""
    return field(default=default, metadata={"unit": unit, "doc": doc, "check": check})


@dataclass(frozen=True)
class AnalysisOptions:
    """Settings of one analysis (:func:`osteon.analyze`, :class:`osteon.Analyzer`,
    :func:`osteon.correct`), checked and normalised when made; ``ValueError`` naming a bad one.
    Equal options give bit-identical results. Make a variant with ``dataclasses.replace``."""

    force: float = _option(20.0, "N", "force on the worst point of each branch",
                           lambda v: _positive(v, "force", "N"))
    allowable_stress: float = _option(
        60.0, "MPa", "allowable stress [sigma] = material strength / safety factor",
        lambda v: _positive(v, "allowable_stress", "MPa"))
    interval: float = _option(2.0, "mm", "spacing of the sections along each bone",
                              lambda v: _positive(v, "interval", "mm"))
    root: int | str | None = _option(
        None, "", "bone (index or name) held at its head; None: the main root bone", _root)
    gap_tolerance: float | None = _option(
        None, "mm", "open cuts are closed across gaps up to this; None: 1 % of the model size",
        _gap_tolerance)
    threads: int = _option(0, "", "worker threads; 0 = all cores",
                           lambda v: _count(v, "threads"))
    local_cuts: bool = _option(
        True, "", "cut near each bone first, the whole plane only when needed (same result, "
        "faster); False always cuts whole planes", bool)
    build_direction: tuple = _option(
        (0.0, 0.0, 1.0), "", "FDM build direction in the model's frame (any non-zero 3-vector, "
        "stored unit): each section's allowable depends on its angle to it (docs/printing.md)",
        _build_direction)
    layer_strength_ratio: float = _option(
        1.0, "", "layer / in-plane strength (1 = isotropic)", _layer_strength_ratio)
    keep_outlines: bool = _option(
        False, "", "also return each section's loops (Analysis.section_loops)", bool)
    min_thickness: float = _option(
        DEFAULT_MIN_THICKNESS, "mm", "sections thinner than this are flagged too_thin "
        "(None: 0.8 mm, FDM; 0 = no check)", _min_thickness)
    junctions: bool = _option(
        True, "", "where a section cuts a side branch's stub, count only the core that "
        "continues through the plane (flag junction, docs/junctions.md); False: whole cuts",
        lambda v: _switch(v, "junctions"))
    print_profile: PrintProfile = _option(  # noqa: RUF009 -- PrintProfile is frozen
        PrintProfile.solid(), "", "how the part is printed: a PrintProfile or a preset's name "
        "(osteon.print_profiles(); None: solid); each section becomes what that print makes of "
        "it (walls, skins, sparse infill in the frame of build_direction, or a resin shell; "
        "docs/printing.md), section_modulus and the stress the printed section's", get_profile)
    notch_sensitivity: float = _option(
        1.0, "", "q, 0..1: at a section next to a concave corner (flag notch) the governing "
        "stress is (1 + q (Kt - 1)) x the beam stress (docs/notch.md); 1 (brittle) is the safe "
        "side, the material presets carry their own", _notch_sensitivity)
    min_notch_radius: float = _option(
        0.2, "mm", "corners sharper than this are taken at this radius, the print rounds them "
        "(None: 0.2 mm, half a 0.4 mm nozzle's line; docs/notch.md)", _min_notch_radius)
    max_sections: int = _option(
        MAX_SECTIONS, "", "refuse before any work (ValueError with the estimate of sections "
        "and memory, ~11 kB each) a run that would make more sections than this for the whole "
        "model: a model in metres read as mm, a tiny interval", _max_sections)

    def __post_init__(self) -> None:
        # The one layer that checks: every value normalised here (the fields' order is the
        # order of the checks); the front ends and the engine wrappers only convert.
        for f in fields(self):
            check = f.metadata["check"]
            if check is not None:
                object.__setattr__(self, f.name, check(getattr(self, f.name)))

    @classmethod
    def of(cls, options: AnalysisOptions | None, settings: dict) -> AnalysisOptions:
        """``options`` or the keyword ``settings`` (not both) as one checked object."""
        if options is None:
            return cls(**settings)
        if not isinstance(options, AnalysisOptions):
            raise ValueError(  # noqa: TRY004 -- every bad argument is a ValueError here
                f"options must be an osteon.AnalysisOptions, got {options!r}")
        if settings:
            raise ValueError(f"give the settings either as options= or as keywords, not both "
                             f"(got {', '.join(sorted(settings))})")
        return options


def option_docs() -> list[tuple[str, str, str]]:
    """(name, unit, doc) of every option, in order (for docstrings)."""
    return [(f.name, f.metadata["unit"], f.metadata["doc"]) for f in fields(AnalysisOptions)]


def engine_options(options: AnalysisOptions, held_bone: int) -> _core.AnalysisOptions:
    """The engine's options object: ``options`` (checked already) and the index of the held
    bone (-1: the main root). One line per engine setting."""
    o = _core.AnalysisOptions()
    o.force = options.force
    o.allowable_stress = options.allowable_stress
    o.interval = options.interval
    o.held_bone = held_bone
    o.gap_tolerance = -1.0 if options.gap_tolerance is None else options.gap_tolerance
    o.threads = options.threads
    o.local_cuts = options.local_cuts
    o.build_direction = list(options.build_direction)
    o.layer_strength_ratio = options.layer_strength_ratio
    o.keep_outlines = options.keep_outlines
    o.min_thickness = options.min_thickness
    o.junctions = options.junctions
    engine_print_options(o, options.print_profile)
    o.notch_sensitivity = options.notch_sensitivity
    o.min_notch_radius = options.min_notch_radius
    # Thickness only where the too_thin check needs it; Analysis.section_thickness computes the
    # rest on first read (a convex hull per section: ~7 % of an analysis nobody may read).
    o.defer_thickness = True
    return o
