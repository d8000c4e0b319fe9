"""osteon: find the parts of a rigged 3D model that will snap once printed, and thicken them.

Skeleton-sectional structural analysis (Xu, Li, Liu) with a C++ engine. Units: millimetres of the
printed object, newtons, MPa. See :func:`analyze`, :func:`correct`, :class:`Skeleton`.
"""

from ._api import (
    DEFAULT_SCALING,
    SECTION_FLAGS,
    SECTION_KINDS,
    Analysis,
    Analyzer,
    Correction,
    Skeleton,
    analyze,
    correct,
    section_properties,
    skin,
    slice_section,
)
from .orientation import Orientation, best_orientation
from .autoskeleton import auto_skeleton

__version__ = "0.1.0"

__all__ = [
    "DEFAULT_SCALING",
    "SECTION_FLAGS",
    "SECTION_KINDS",
    "Analysis",
    "Analyzer",
    "Correction",
    "Orientation",
    "Skeleton",
    "analyze",
    "best_orientation",
    "auto_skeleton",
    "correct",
    "section_properties",
    "skin",
    "slice_section",
]
