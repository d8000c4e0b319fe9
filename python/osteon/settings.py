"""One set of user settings and the one mapping from settings to the engine's arguments.

The CLI (from its options), the Blender add-on (from ``scene.osteon``), live mode and batch runs
all build a :class:`Settings` and call :func:`engine_arguments`; the checks live here once.
Units: mm, N, MPa.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

from . import materials, profiles
from .options import (  # noqa: F401 -- the global budget, re-exported for the front ends
    BYTES_PER_SECTION,
    MAX_SECTIONS,
    AnalysisOptions,
    _length_text,
    _switch,
    section_budget,
)
from .profiles import PrintProfile, resolve_profile
from .report import allowable_stress


@dataclass(frozen=True)
class Settings:
    """What the user chose.

    ``material``: a preset key of :mod:`osteon.materials` (or ``CUSTOM``); ``strength_mpa``:
    the strength in MPa (``None``: the preset's); ``safety_factor``: allowable stress =
    strength / safety factor; ``force_n``: N on the worst point of each branch;
    ``interval_mm``: mm between sections; ``held_bone``: bone name or index held at its head
    (``None`` or ``""``: the main root); ``size_mode``/``print_size_mm``: how the model's units
    become mm (front-end specific: "HEIGHT", "LARGEST", "UNITS", "X", "Y"); ``max_scale``,
    ``max_rounds``, ``scaling``: the correction's limits and mode ("thin"/"uniform");
    ``build_direction`` (3,) the FDM build direction in the model's frame and
    ``layer_strength_ratio`` layer / in-plane strength (1.0 isotropic, ``None`` = the material
    preset's; docs/printing.md); ``junctions`` (default True): where a section cuts a side
    branch's stub, count only the core that continues through the plane (flag ``junction``,
    docs/junctions.md); False analyses whole cuts (faster, no junction stage).

    Print profile (docs/printing.md, "Print profiles"): ``print_profile`` a preset key of
    :func:`osteon.profiles.print_profiles` (default "solid": the section as cut, the numbers
    before issue 31), with optional overrides (``None`` = the preset's): ``perimeters``
    (count), ``infill`` (fraction 0…1), ``infill_pattern``, ``line_width_mm``,
    ``layer_height_mm``, ``top_bottom_layers`` (count) for FDM presets, ``shell_mm`` for a
    hollowed resin preset. :meth:`profile` resolves them into one checked
    :class:`osteon.profiles.PrintProfile`.

    ``notch_sensitivity`` q (0…1) at corners and ``min_notch_radius_mm`` (mm), ``None``: the
    material preset's (docs/notch.md; a custom strength: q = 1, 0.2 mm).
    """

    force_n: float
    interval_mm: float
    material: str = materials.DEFAULT_MATERIAL
    strength_mpa: float | None = None
    safety_factor: float = materials.DEFAULT_SAFETY_FACTOR
    held_bone: str | int | None = None
    size_mode: str = "LARGEST"
    print_size_mm: float = 120.0
    max_scale: float = 3.0
    max_rounds: int = 100
    scaling: str = "thin"
    build_direction: tuple = (0.0, 0.0, 1.0)
    layer_strength_ratio: float | None = 1.0
    junctions: bool = True
    print_profile: str = "solid"
    perimeters: int | None = None
    infill: float | None = None
    infill_pattern: str | None = None
    line_width_mm: float | None = None
    layer_height_mm: float | None = None
    top_bottom_layers: int | None = None
    shell_mm: float | None = None

    def profile(self) -> PrintProfile:
        """The print profile: the preset with the overrides applied (``ValueError`` naming a bad
        value or an override the preset's kind has no use for)."""
        return resolve_profile(self.print_profile,
                               {f: getattr(self, f) for f in profiles.OVERRIDES})
    notch_sensitivity: float | None = None
    min_notch_radius_mm: float | None = None

    def layer_ratio(self) -> float:
        """Layer / in-plane strength used: the given one; ``None``: the material preset's (1.0
        for a custom strength)."""
        if self.layer_strength_ratio is not None:
            return float(self.layer_strength_ratio)
        if self.strength_mpa is not None and str(self.material).upper() == materials.CUSTOM:
            return 1.0
        try:
            return materials.get(self.material).layer_strength_ratio
        except ValueError:
            return 1.0

    def material_and_strength(self) -> tuple[str, float]:
        """(material key, strength in MPa): the given strength, else the preset's."""
        if self.strength_mpa is not None:
            key = self.material
            if str(key).upper() != materials.CUSTOM:
                key = materials.get(key).key
            return key, float(self.strength_mpa)
        m = materials.get(self.material)
        return m.key, m.strength_mpa

    def allowable_stress_mpa(self) -> float:
        """strength / safety factor, MPa (``ValueError`` when either is not positive)."""
        return allowable_stress(self.material_and_strength()[1], self.safety_factor)

    def as_dict(self) -> dict:
        """JSON-ready, with the strength resolved (the report's ``settings``)."""
        d = asdict(self)
        d["material"], d["strength_mpa"] = self.material_and_strength()
        d["safety_factor"] = float(self.safety_factor)
        d["held_bone"] = "" if self.held_bone is None else self.held_bone
        d["scaling"] = str(self.scaling).upper()
        d["build_direction"] = [float(x) for x in self.build_direction]
        d["layer_strength_ratio"] = self.layer_ratio()
        d["junctions"] = _switch(self.junctions, "junctions")
        d["print_profile"] = str(self.print_profile).strip().lower()
        d["notch_sensitivity"] = notch_sensitivity(self)
        # the radius the engine is given (an FDM profile's half line width; engine_arguments)
        d["min_notch_radius_mm"] = min_notch_radius_mm(self, self.profile())
        return d


#: the axis choices of the front ends (Blender's "Print direction"), unit vectors in the
#: model's (scene's) frame
AXES = {"+X": (1.0, 0.0, 0.0), "-X": (-1.0, 0.0, 0.0), "+Y": (0.0, 1.0, 0.0),
        "-Y": (0.0, -1.0, 0.0), "+Z": (0.0, 0.0, 1.0), "-Z": (0.0, 0.0, -1.0)}


def axis_direction(axis: str) -> tuple:
    """The build direction (3,) of an axis name ("+X" ... "-Z"); ``ValueError`` otherwise."""
    try:
        return AXES[str(axis).upper()]
    except KeyError:
        raise ValueError(f"print axis must be one of {', '.join(AXES)}, got {axis!r}") from None


#: The options' names as the front ends word them (the CLI maps these words to its flags).
_FRONT_END_WORDS = {"interval": "section interval",
                    "layer_strength_ratio": "layer strength ratio",
                    "build_direction": "build direction",
                    "notch_sensitivity": "notch sensitivity",
                    "min_notch_radius": "min notch radius"}


def _checked(kw: dict) -> AnalysisOptions:
    """The settings as checked :class:`osteon.AnalysisOptions` (the one place they are checked);
    ``ValueError`` naming the setting as the front ends do."""
    try:
        return AnalysisOptions(**kw)
    except ValueError as e:
        msg = str(e)
        name = msg.split(" ", 1)[0]
        raise ValueError(_FRONT_END_WORDS.get(name, name) + msg[len(name):]) from None


def held_bone_index(held_bone, bone_names) -> int | None:
    """Index of the held bone: ``None``/"" -> None (the main root), a name or an index."""
    if held_bone is None or held_bone == "":
        return None
    names = list(bone_names)
    if isinstance(held_bone, str) and held_bone.lstrip("-").isdigit() and held_bone not in names:
        held_bone = int(held_bone)
    if isinstance(held_bone, int):
        if not (0 <= held_bone < len(names)):
            raise ValueError(f"Held bone index {held_bone} is out of range: "
                             f"the skeleton has {len(names)} bones")
        return held_bone
    if held_bone not in names:
        raise ValueError(f"Held bone {str(held_bone)!r} is not one of the skeleton's bones "
                         f"({', '.join(names[:12])}{' ...' if len(names) > 12 else ''})")
    return names.index(held_bone)


def min_thickness_mm(settings: Settings) -> float:
    """Minimum printable thickness in mm: the material preset's (0.8 mm for a custom one)."""
    try:
        return float(materials.get(settings.material).min_thickness_mm)
    except (KeyError, ValueError):
        return 0.8


def _preset(settings: Settings):
    try:
        return materials.get(settings.material)
    except (KeyError, ValueError):
        return None


def notch_sensitivity(settings: Settings) -> float:
    """q used at corners: the given one, else the material preset's (1 for a custom strength)."""
    if settings.notch_sensitivity is not None:
        return settings.notch_sensitivity
    m = _preset(settings)
    return 1.0 if m is None else m.notch_sensitivity


def min_notch_radius_mm(settings: Settings, profile=None) -> float:
    """Smallest corner radius in mm: the given one; else the print profile's (FDM: half its
    line width, the rule of docs/notch.md); else the material preset's (0.2 mm when custom)."""
    if settings.min_notch_radius_mm is not None:
        return settings.min_notch_radius_mm
    if profile is not None and getattr(profile, "kind", "") == "fdm":
        return 0.5 * float(profile.line_width)
    m = _preset(settings)
    return 0.2 if m is None else float(m.min_notch_radius_mm)


def engine_arguments(settings: Settings, bone_names, correct: bool = False) -> dict:
    """The keyword arguments of ``osteon.analyze`` / ``Analyzer`` (``force``,
    ``allowable_stress``, ``interval``, ``root``, ``build_direction``,
    ``layer_strength_ratio``, ``min_thickness``, ``junctions``, ``notch_sensitivity``,
    ``min_notch_radius``, and ``print_profile`` unless the profile is solid), plus
    ``max_scale``, ``max_rounds``, ``scaling`` with ``correct=True`` for ``osteon.correct``.
    Raises ``ValueError`` naming the bad setting."""
    profile = settings.profile()
    kw = {
        "force": settings.force_n,
        "allowable_stress": settings.allowable_stress_mpa(),
        "interval": settings.interval_mm,
        "root": held_bone_index(settings.held_bone, bone_names),
        "build_direction": settings.build_direction,
        "layer_strength_ratio": settings.layer_ratio(),
        "min_thickness": min_thickness_mm(settings),
        "junctions": settings.junctions,
        "notch_sensitivity": notch_sensitivity(settings),
        "min_notch_radius": min_notch_radius_mm(settings, profile),
    }
    options = _checked(kw)
    kw.update((name, getattr(options, name)) for name in kw)
    # as given (analyze makes it a unit vector): the report shows the user's numbers
    kw["build_direction"] = [float(x) for x in settings.build_direction]
    if not profile.is_solid:  # solid: no argument, the engine's default (bit for bit)
        kw["print_profile"] = profile
    if correct:
        if not (float(settings.max_scale) >= 1.0):
            raise ValueError(f"max scale must be >= 1, got {settings.max_scale}")
        if int(settings.max_rounds) < 0:
            raise ValueError(f"max rounds must be >= 0, got {settings.max_rounds}")
        kw.update(max_scale=float(settings.max_scale), max_rounds=int(settings.max_rounds),
                  scaling=str(settings.scaling).lower())
    return kw


#: Sections above which the front ends ask before analysing (the Blender add-on's preference
#: "Section limit", the CLI's ``--max-sections``): ~10 s of analysis on a typical model, and
#: a sign that the print size is wrong (a model in metres read as mm).
SECTION_LIMIT = 20_000


def section_guard(sections: int, interval_mm: float, model_size_mm: float,
                  limit: int = SECTION_LIMIT) -> str | None:
    """``None`` when ``sections`` (from :func:`osteon.estimate_sections`) is within ``limit``,
    else the warning the front ends show before starting, e.g. "2 623 469 sections at 2 mm on
    a 2.45 km model: check the print size (limit 20 000)". ``model_size_mm``: the model's
    largest printed dimension, mm."""
    if int(sections) <= int(limit):
        return None

    def grouped(n: int) -> str:
        return f"{int(n):,}".replace(",", " ")

    return (f"{grouped(sections)} sections at {float(interval_mm):g} mm on a "
            f"{_length_text(float(model_size_mm))} model: check the print size "
            f"(limit {grouped(limit)})")
