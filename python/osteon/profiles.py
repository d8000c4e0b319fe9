"""Print profiles: what the printer makes of the model (walls, skins, infill, hollow shells).

The one table of print profiles, beside :mod:`osteon.materials`, shared by the Python API, the
CLI, batch runs and the Blender add-on. A profile says how the part is printed; the engine turns
each section into what that print makes of it (docs/printing.md, "The printed section").

Units: mm for lengths (``line_width``, ``layer_height``, ``shell``), mm² for areas
(``solid_infill_below_area``), a fraction 0…1 for ``infill``, counts for ``perimeters`` and
``top_bottom_layers``.

Kinds:

- ``"solid"``: the part is solid (SLS, or a 100 %-infill FDM part; osteon's behaviour before
  print profiles, bit for bit).
- ``"fdm"``: ``perimeters`` loops of ``line_width`` around each layer (``layer_height``),
  ``top_bottom_layers`` solid layers above and below, ``infill`` of ``pattern`` inside; regions
  of a layer smaller than ``solid_infill_below_area`` are filled solid (PrusaSlicer's rule).
- ``"resin_hollow"``: a hollowed resin print: a solid shell ``shell`` mm thick, hollow inside.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

#: Infill patterns the effective-stiffness law knows (docs/printing.md, "Infill").
PATTERNS = ("gyroid", "grid", "rectilinear", "cubic", "honeycomb", "triangles", "lines")

KINDS = ("solid", "fdm", "resin_hollow")


def _count(value, name: str, low: int = 0, high: int = 1000) -> int:
    if isinstance(value, bool) or not float(value).is_integer():
        raise ValueError(f"{name} must be a whole number, got {value!r}")
    v = int(value)
    if not low <= v <= high:
        raise ValueError(f"{name} must be between {low} and {high}, got {value!r}")
    return v


def _length(value, name: str, unit: str = "mm", allow_zero: bool = False) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number of {unit}, got {value!r}") from None
    ok = (v >= 0.0) if allow_zero else (v > 0.0)
    if not (ok and math.isfinite(v)):
        sign = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"{name} must be a finite number {sign} {unit}, got {value!r}")
    return v


@dataclass(frozen=True)
class PrintProfile:
    """How a part is printed. Build one with :meth:`fdm`, :meth:`resin_hollow` or :meth:`solid`
    (checked there: ``ValueError`` naming the bad value), or take a preset from
    :func:`print_profiles`.

    ``kind``: "solid", "fdm" or "resin_hollow"; ``perimeters``: wall loops per layer (count);
    ``line_width``: extrusion width, mm; ``layer_height``: mm; ``top_bottom_layers``: solid
    layers at the top and bottom surfaces (count); ``infill``: sparse infill density, fraction
    0…1; ``pattern``: infill pattern (one of :data:`PATTERNS`); ``solid_infill_below_area``: mm²,
    a layer region whose infill area is below this is filled solid (0 = never); ``shell``: mm,
    the resin shell of a hollowed print; ``skin_growth_lines``: with sparse infill, skin strips
    narrower than twice this many line widths are widened by it into the infill (PrusaSlicer's
    rule: 3; 0 = not modelled); ``name`` and ``source``: the preset's name and where its
    numbers come from.
    """

    kind: str = "solid"
    perimeters: int = 0
    line_width: float = 0.0
    layer_height: float = 0.0
    top_bottom_layers: int = 0
    infill: float = 1.0
    pattern: str = "gyroid"
    solid_infill_below_area: float = 0.0
    shell: float = 0.0
    skin_growth_lines: float = 0.0
    name: str = "solid"
    source: str = ""

    @classmethod
    def fdm(cls, perimeters: int = 2, line_width: float = 0.45, layer_height: float = 0.2,
            top_bottom_layers: int = 4, infill: float = 0.15, pattern: str = "gyroid",
            solid_infill_below_area: float = 70.0, *, skin_growth_lines: float = 3.0,
            name: str = "fdm", source: str = "") -> PrintProfile:
        """An FDM print: counts, mm, mm, layers, fraction 0…1, pattern name, mm².
        ``skin_growth_lines``: with sparse infill, a skin strip narrower than twice this many
        line widths is widened by that much into the infill (PrusaSlicer's rule, 3; 0: not
        modelled, the safe side)."""
        pattern = str(pattern).strip().lower()
        if pattern not in PATTERNS:
            raise ValueError(f"unknown infill pattern {pattern!r}; choose one of "
                             f"{', '.join(PATTERNS)}")
        try:
            fill = float(infill)
        except (TypeError, ValueError):
            raise ValueError(f"infill must be a fraction 0..1, got {infill!r}") from None
        if not (0.0 <= fill <= 1.0):
            raise ValueError(f"infill must be a fraction 0..1 (0.15 = 15 %), got {infill!r}")
        return cls(kind="fdm",
                   perimeters=_count(perimeters, "perimeters", 0, 100),
                   line_width=_length(line_width, "line_width"),
                   layer_height=_length(layer_height, "layer_height"),
                   top_bottom_layers=_count(top_bottom_layers, "top_bottom_layers", 0, 1000),
                   infill=fill, pattern=pattern,
                   solid_infill_below_area=_length(solid_infill_below_area,
                                                   "solid_infill_below_area", "mm²",
                                                   allow_zero=True),
                   skin_growth_lines=_length(skin_growth_lines, "skin_growth_lines", "lines",
                                             allow_zero=True),
                   name=str(name), source=str(source))

    @classmethod
    def resin_hollow(cls, shell: float = 2.0, *, name: str = "resin_hollow",
                     source: str = "") -> PrintProfile:
        """A hollowed resin print with a solid shell ``shell`` mm thick."""
        return cls(kind="resin_hollow", shell=_length(shell, "shell"), infill=0.0,
                   name=str(name), source=str(source))

    @classmethod
    def solid(cls) -> PrintProfile:
        """A solid part (SLS, or 100 % infill): the section as cut, osteon's default."""
        return cls(kind="solid", name="solid",
                   source="the part is solid: the section as cut (SLS, 100 % infill)")

    @property
    def is_solid(self) -> bool:
        """True when every section is its solid cut (kind "solid", or FDM at 100 % infill)."""
        return self.kind == "solid" or (self.kind == "fdm" and self.infill >= 1.0)

    def with_changes(self, **changes) -> PrintProfile:
        """A copy with some fields changed, checked again (e.g. ``perimeters=4``)."""
        p = replace(self, **changes)
        if p.kind == "fdm":
            return PrintProfile.fdm(p.perimeters, p.line_width, p.layer_height,
                                    p.top_bottom_layers, p.infill, p.pattern,
                                    p.solid_infill_below_area,
                                    skin_growth_lines=p.skin_growth_lines, name=p.name,
                                    source=p.source)
        if p.kind == "resin_hollow":
            return PrintProfile.resin_hollow(p.shell, name=p.name, source=p.source)
        if p.kind == "solid":
            return PrintProfile.solid()
        raise ValueError(f"unknown print profile kind {p.kind!r}; one of {', '.join(KINDS)}")

    def as_dict(self) -> dict:
        """JSON-ready (the report's ``print_profile``)."""
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> PrintProfile:
        """The profile of :meth:`as_dict` (checked)."""
        try:
            kind = d["kind"]
        except (KeyError, TypeError):
            raise ValueError("a print profile needs a 'kind' (solid, fdm, resin_hollow)") from None
        known = {k: d[k] for k in cls.__dataclass_fields__ if k in d}
        return cls(**{**cls().__dict__, **known, "kind": kind}).with_changes()


# The presets: each number from the slicer's own profile file (file, profile name and key in
# ``source``), for a 0.4 mm nozzle at 0.2 mm layers. Mapping rules (docs/printing.md, "Presets"):
# - perimeters: PrusaSlicer ``perimeters``, Bambu/Orca ``wall_loops``, Cura ``wall_line_count``.
# - line_width: the perimeter (wall) extrusion width; where the outer and inner walls differ
#   (Bambu 0.42 / 0.45 mm) the smaller, so the wall band is never thicker than printed.
# - top_bottom_layers: where top ≠ bottom (PrusaSlicer 5 / 4, Bambu 5 / 3) the smaller: a
#   section across the layers is only as strong as its thinner skin (conservative).
# - solid_infill_below_area: PrusaSlicer ``solid_infill_below_area``, Bambu/Orca
#   ``minimum_sparse_infill_area`` (the same rule: a sparse region below that area is printed
#   solid); Cura has ``min_infill_area`` ("use skin instead", default 0 = never).
_PRUSA_INI = ("PrusaSlicer resources/profiles/PrusaResearch.ini (PrusaSlicer 2.9.4, "
              "commit 69c8e56), [print:0.20mm QUALITY @MK3] with its parents *0.20mm* and "
              "*common*")
_BAMBU_DIR = "BambuStudio resources/profiles/BBL/process/"
_CURA_DEF = "Cura resources/definitions/fdmprinter.def.json"


def _presets() -> dict[str, PrintProfile]:
    return {
        "prusaslicer": PrintProfile.fdm(
            perimeters=2, line_width=0.45, layer_height=0.2, top_bottom_layers=4, infill=0.15,
            pattern="gyroid", solid_infill_below_area=0.0, skin_growth_lines=0.0,
            name="PrusaSlicer 0.20mm QUALITY @MK3",
            source=(f"{_PRUSA_INI}: perimeters = 2, perimeter_extrusion_width = "
                    "external_perimeter_extrusion_width = 0.45 (*common*); layer_height = 0.2, "
                    "top_solid_layers = 5, bottom_solid_layers = 4 (*0.20mm*; the smaller, 4, "
                    "taken); fill_density = 15%, fill_pattern = gyroid (0.20mm QUALITY @MK3); "
                    "solid_infill_below_area = 0 (*common*; PrusaSlicer's built-in default "
                    "without a profile is 70 mm², src/libslic3r/PrintConfig.cpp); "
                    "ensure_vertical_shell_thickness = 1 (*common*): PrusaSlicer then skips "
                    "the narrow-skin widening of discover_horizontal_shells, so "
                    "skin_growth_lines = 0")),
        "bambustudio": PrintProfile.fdm(
            perimeters=2, line_width=0.42, layer_height=0.2, top_bottom_layers=3, infill=0.15,
            pattern="grid", solid_infill_below_area=15.0, skin_growth_lines=0.0,
            name="Bambu Studio 0.20mm Standard @BBL X1C",
            source=(f"{_BAMBU_DIR}0.20mm Standard @BBL X1C.json → fdm_process_single_0.20.json "
                    "→ fdm_process_common.json: wall_loops = 2, outer_wall_line_width = 0.42, "
                    "inner_wall_line_width = 0.45 (the smaller, 0.42, taken), layer_height = "
                    "0.2, top_shell_layers = 5 (fdm_process_single_0.20), bottom_shell_layers "
                    "= 3 (the smaller, 3, taken), sparse_infill_density = 15%, "
                    "sparse_infill_pattern = grid, minimum_sparse_infill_area = 15 (mm²; "
                    "OrcaSlicer's own BBL copy has crosshatch and 0); "
                    "ensure_vertical_shell_thickness = 1 (Bambu's G-code headers): no "
                    "narrow-skin widening, skin_growth_lines = 0")),
        "cura": PrintProfile.fdm(
            perimeters=2, line_width=0.4, layer_height=0.2, top_bottom_layers=4, infill=0.20,
            pattern="grid", solid_infill_below_area=0.0, skin_growth_lines=0.0,
            name="Cura defaults (fdmprinter) at 0.2 mm layers",
            source=(f"{_CURA_DEF}: line_width = machine_nozzle_size = 0.4; wall_thickness = "
                    "0.8 → wall_line_count = round((0.8 - 0.4) / 0.4) + 1 = 2; "
                    "top_bottom_thickness = 0.8 → top_layers = bottom_layers = ceil(0.8 / 0.2) "
                    "= 4 at 0.2 mm layers (fdmprinter's own layer_height is 0.1, the machines' "
                    "quality profiles set it); infill_sparse_density = 20, infill_pattern = "
                    "grid ('lines' only above 25 %); min_infill_area = 0 (no small-area rule)")),
        "resin_hollow": PrintProfile.resin_hollow(
            shell=2.0, name="Resin, hollowed, 2 mm shell",
            source=("2 mm: the thin end of the 2-3 mm shells that resin hollowing guides advise "
                    "for Lychee and Chitubox (resinandrolls.com, 'How to hollow resin "
                    "miniatures'), taken because a thinner shell is the weaker (conservative); "
                    "PrusaSlicer's SLA hollowing default is 3 mm (hollowing_min_thickness, "
                    "src/libslic3r/PrintConfig.cpp): use --shell 3 for it")),
        "solid": PrintProfile.solid(),
    }


def print_profiles() -> dict[str, PrintProfile]:
    """The named presets ``{key: PrintProfile}``, each with its ``source``."""
    return dict(_presets())


def get_profile(name: str | PrintProfile | None) -> PrintProfile:
    """A preset by key (case-insensitive), a :class:`PrintProfile` as it is, or ``None`` → solid.

    ``ValueError`` naming the presets when there is none by that name."""
    if name is None:
        return PrintProfile.solid()
    if isinstance(name, PrintProfile):
        return name
    presets = print_profiles()
    key = str(name).strip().lower()
    if key not in presets:
        raise ValueError(f"unknown print profile {name!r}; choose one of {', '.join(presets)}")
    return presets[key]


#: The overrides of a preset, by their ``osteon.settings.Settings`` field: (the PrintProfile
#: field, the kind that uses it)
OVERRIDES = {"perimeters": ("perimeters", "fdm"), "infill": ("infill", "fdm"),
             "infill_pattern": ("pattern", "fdm"), "line_width_mm": ("line_width", "fdm"),
             "layer_height_mm": ("layer_height", "fdm"),
             "top_bottom_layers": ("top_bottom_layers", "fdm"),
             "shell_mm": ("shell", "resin_hollow")}


def resolve_profile(key, overrides: dict | None = None) -> PrintProfile:
    """The preset ``key`` with ``overrides`` ({Settings field: value or None}) applied and
    checked; the name says what changed ("prusaslicer, perimeters 3"). The one resolution every
    front end and the report use."""
    base = get_profile(key if key not in (None, "") else "solid")
    given = {k: v for k, v in (overrides or {}).items() if v is not None and v != ""}
    unknown = sorted(set(given) - set(OVERRIDES))
    if unknown:
        raise ValueError(f"unknown print setting(s) {', '.join(unknown)}")
    if not given:
        return base
    wrong = [k for k in given if OVERRIDES[k][1] != base.kind]
    if wrong:
        needs = {OVERRIDES[k][1] for k in wrong}
        hint = ("an FDM profile (e.g. prusaslicer)" if needs == {"fdm"}
                else "a resin profile (resin_hollow)")
        raise ValueError(f"{wrong[0]} needs {hint}; print profile {key!r} is {base.kind}")
    changes = {OVERRIDES[k][0]: v for k, v in given.items()}
    label = ", ".join(f"{OVERRIDES[k][0]} {v:g}" if isinstance(v, (int, float)) else
                      f"{OVERRIDES[k][0]} {v}" for k, v in given.items())
    return base.with_changes(name=f"{base.name}, {label}", **changes)


def profile_of(settings: dict) -> PrintProfile:
    """The print profile of a settings dict (:meth:`osteon.settings.Settings.as_dict` or a
    front end's own; missing keys: the preset's, no key: solid)."""
    return resolve_profile(settings.get("print_profile"),
                           {k: settings.get(k) for k in OVERRIDES})
