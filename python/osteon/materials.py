"""The one table of print materials, shared by the CLI, the Blender add-on and batch runs.

Units: MPa for strengths, mm for thicknesses. Every number carries its source.

Strengths are the tensile (yield) strength of *printed* parts along the layers (FDM) or of the
cured/sintered part (resin, SLS), as manufacturers' data sheets list them. Across FDM layers a
part is weaker: ``layer_strength_ratio`` (Z / XY strength, issue 18) is used by the layer
model of docs/printing.md when a front end asks for the material's ratio.

Decision (issue 15): before this table the CLI had nylon at 70 MPa with a safety factor of 1 and
the add-on nylon at 48 MPa with a safety factor of 2, so PLA's default allowable stress was 60 MPa
in one front end and 30 MPa in the other. Kept: the printed-part numbers (70 MPa is moulded
PA6/PA66, not a printed part; printed nylon is SLS PA12, 48 MPa on EOS PA 2200's data sheet) and
one default safety factor of 2 for every front end: the paper (§6) takes the allowable stress
equal to PLA's 60 MPa yield strength on a lab bench, but a consumer print has layer seams, voids
and a load we only estimate, and an FDM part across its layers holds about half its XY strength.
"""

from __future__ import annotations

from dataclasses import dataclass

#: allowable stress = strength / safety factor, in every front end (see the module note).
DEFAULT_SAFETY_FACTOR = 2.0
#: the preset every front end starts from
DEFAULT_MATERIAL = "PLA"
#: the key of "my own strength" (no preset numbers): the CLI's --strength-mpa, the add-on's Custom
CUSTOM = "CUSTOM"

#: The print profile (a key of :func:`osteon.profiles.print_profiles`) each process suggests:
#: FDM → PrusaSlicer's 0.20mm QUALITY defaults (2 perimeters, 15 % gyroid), resin → a hollowed
#: print with a 2 mm shell, SLS → solid (a sintered part has no infill). A suggestion only: the
#: front ends analyse solid unless asked (issue 31), and show this key as the one to try.
DEFAULT_PROFILE_BY_PROCESS = {"FDM": "prusaslicer", "resin": "resin_hollow", "SLS": "solid"}


@dataclass(frozen=True)
class Material:
    """One print material.

    ``strength_mpa``: tensile strength in MPa of a printed part (along the layers for FDM);
    ``layer_strength_ratio``: strength across the layers / ``strength_mpa`` (1 = no weaker;
    sources in ``layer_strength_source`` and docs/printing.md); ``min_thickness_mm``: thinnest wall in mm the process prints
    reliably (used by the printability check of issue 12).
    """

    key: str
    label: str
    process: str  # "FDM", "resin" (SLA/DLP/MSLA) or "SLS"
    strength_mpa: float
    strength_source: str
    layer_strength_ratio: float
    layer_strength_source: str
    min_thickness_mm: float
    min_thickness_source: str
    note: str

    @property
    def default_profile(self) -> str:
        """The print profile key this material's process suggests
        (:data:`DEFAULT_PROFILE_BY_PROCESS`)."""
        return DEFAULT_PROFILE_BY_PROCESS[self.process]


_PLA_LAYER = ("Polymaker PolyTerra PLA TDS v5.3: tensile X-Y 23.2 MPa, Z 12.2 MPa (0.53); "
              "published FDM PLA XY 50-65 / Z 35-45 MPa (0.54-0.9); docs/printing.md")
_PETG_LAYER = "published FDM PETG XY 44-56 / Z 25-38 MPa (0.45-0.86, mid 0.6); docs/printing.md"
_ABS_LAYER = ("Ahn et al. 2002, Torrado Perez et al. 2015: FDM ABS bonds between roads fail "
              "first, similar to or below PLA; docs/printing.md")
_SLS_LAYER = "SLS parts are near-isotropic; treated as isotropic (docs/printing.md)"
_FDM_WALL = "two perimeters of a 0.4 mm nozzle (FDM design rules: supported walls >= 0.8 mm)"
_RESIN_WALL = "Formlabs design guide: supported walls 0.2 mm, unsupported 0.4 mm"
_SLS_WALL = "SLS design rules (Hubs, EOS): walls >= 0.7 mm"

MATERIALS: tuple[Material, ...] = (
    Material("PLA", "PLA", "FDM", 60.0,
             "paper §6 (PLA yield 60 MPa); Prusament PLA data sheet: yield 57 ± 1 MPa",
             0.55, _PLA_LAYER, 0.8, _FDM_WALL, "FDM PLA, ~50-65 MPa along layers"),
    Material("PETG", "PETG", "FDM", 50.0,
             "Prusament PETG data sheet: yield 47 ± 2 MPa; FDM PETG data sheets 45-55 MPa",
             0.6, _PETG_LAYER, 0.8, _FDM_WALL, "FDM PETG, ~45-55 MPa"),
    Material("ABS", "ABS", "FDM", 40.0,
             "FDM ABS data sheets (e.g. Ultimaker ABS, Prusament ASA): 35-45 MPa at yield",
             0.5, _ABS_LAYER, 0.8, _FDM_WALL, "FDM ABS, ~35-45 MPa"),
    Material("RESIN", "Resin", "resin", 45.0,
             "standard SLA/DLP resins: Formlabs Grey V4 65 MPa post-cured (38 green), "
             "hobby MSLA resins 30-50 MPa; 45 MPa is a cured mid value",
             1.0, "resin parts are near-isotropic", 0.3, _RESIN_WALL,
             "standard SLA/DLP resin, ~40-65 MPa"),
    Material("NYLON", "Nylon (PA12)", "SLS", 48.0,
             "EOS PA 2200 (SLS PA12) data sheet: tensile strength 48 MPa",
             1.0, _SLS_LAYER, 0.7, _SLS_WALL, "SLS PA12, ~45-50 MPa"),
)

_BY_KEY = {m.key: m for m in MATERIALS}


def keys() -> list[str]:
    """The preset keys, in table order (``CUSTOM`` not included)."""
    return [m.key for m in MATERIALS]


def strengths_mpa() -> dict[str, float]:
    """``{key: strength in MPa}`` of every preset."""
    return {m.key: m.strength_mpa for m in MATERIALS}


def get(name: str) -> Material:
    """The preset called ``name`` (case-insensitive: "pla", "Resin", "nylon" ...).

    Raises ``ValueError`` naming the presets when there is none by that name."""
    m = _BY_KEY.get(str(name).strip().upper())
    if m is None:
        raise ValueError(
            f"unknown material {name!r}; choose one of {', '.join(keys())} "
            "or give your own strength in MPa"
        )
    return m
