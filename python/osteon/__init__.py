"""osteon: find the parts of a rigged 3D model that will snap once printed, and thicken them.

Skeleton-sectional structural analysis (Xu, Li, Liu) with a C++ engine. Units: millimetres of the
printed object, newtons, MPa. See :func:`analyze`, :func:`correct`, :class:`Skeleton`.
"""

from ._api import (
    DEFAULT_MIN_THICKNESS,
    DEFAULT_SCALING,
    FLAG_REASONS,
    RESULT_FIELDS,
    SECTION_FLAGS,
    SECTION_KINDS,
    Analysis,
    AnalysisOptions,
    Analyzer,
    Cancelled,
    Correction,
    Progress,
    Skeleton,
    analyze,
    correct,
    estimate_sections,
    section_properties,
    skin,
    slice_section,
)
from .autoskeleton import auto_skeleton
from .orientation import Orientation, best_orientation
from .profiles import PrintProfile, print_profiles
from .reinforcement import Reinforcement, reinforce

__version__ = "0.1.0"

__all__ = [
    "DEFAULT_MIN_THICKNESS",
    "DEFAULT_SCALING",
    "FLAG_REASONS",
    "RESULT_FIELDS",
    "SECTION_FLAGS",
    "SECTION_KINDS",
    "Analysis",
    "AnalysisOptions",
    "Analyzer",
    "Cancelled",
    "Correction",
    "Orientation",
    "PrintProfile",
    "Progress",
    "Reinforcement",
    "Skeleton",
    "analyze",
    "auto_skeleton",
    "best_orientation",
    "correct",
    "estimate_sections",
    "print_profiles",
    "reinforce",
    "section_properties",
    "skin",
    "slice_section",
]
