"""The settings of a batch run (the same as ``osteon analyze`` / ``correct``), in mm, N, MPa."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields, replace


@dataclass(frozen=True)
class BatchSettings:
    """What every model of a batch is analysed with. Units: mm, N, MPa.

    ``height_mm``: printed size of the model's largest bounding-box side (or of its extent along
    ``axis``: 'x', 'y', 'z'; None = longest); ``force_n``: force on the worst point of each
    branch; ``material`` (a preset name) or ``strength_mpa`` (overrides it) and
    ``safety_factor``: allowable stress = strength / factor; ``interval_mm``: distance between
    sections; ``root``: bone name or index held at its head (None: the main root bone);
    ``correct``: also run the correction (``max_scale``, ``max_rounds``, ``scaling``) and write
    the corrected mesh; ``png``: render the stress picture (``png_dpi``); ``allow_open``: analyse
    open meshes too (flagged) instead of failing them; ``engine_threads``: threads of the engine
    inside one task (1: the batch runs models in parallel instead; 0: all cores).
    """

    height_mm: float | None = 120.0
    axis: str | None = None
    force_n: float = 20.0
    material: str = "PLA"
    strength_mpa: float | None = None
    safety_factor: float = 1.0
    interval_mm: float = 2.0
    root: str | int | None = None
    correct: bool = False
    max_scale: float = 3.0
    max_rounds: int = 100
    scaling: str | None = None
    png: bool = True
    png_dpi: int = 60
    allow_open: bool = False
    engine_threads: int = 1

    @classmethod
    def from_any(cls, settings) -> BatchSettings:
        """A BatchSettings from None, a BatchSettings or a dict of its fields."""
        if settings is None:
            return cls()
        if isinstance(settings, cls):
            return settings
        if isinstance(settings, dict):
            names = {f.name for f in fields(cls)}
            unknown = sorted(set(settings) - names)
            if unknown:
                raise ValueError(
                    f"unknown batch setting(s) {', '.join(unknown)}; known: {', '.join(sorted(names))}"
                )
            return cls(**settings)
        raise ValueError(f"settings must be a BatchSettings or a dict, got {type(settings).__name__}")

    def replace(self, **kw) -> BatchSettings:
        return replace(self, **kw)

    def as_dict(self) -> dict:
        return asdict(self)

    def material_and_allowable(self) -> tuple[str, float, float]:
        """(material name, strength MPa, allowable stress MPa); ValueError on bad values."""
        from .._materials_shim import material_strength

        material, strength = material_strength(self.material, self.strength_mpa)
        if not (self.safety_factor > 0 and math.isfinite(self.safety_factor)):
            raise ValueError(f"safety factor must be positive, got {self.safety_factor}")
        return material, strength, strength / self.safety_factor

    def check(self) -> None:
        """Raise ValueError naming the first bad setting (before any model is read)."""
        self.material_and_allowable()
        for name, unit in (("force_n", "N"), ("interval_mm", "mm")):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and v > 0 and math.isfinite(v)):
                raise ValueError(f"{name} must be a positive number of {unit}, got {v}")
        if self.height_mm is not None and not (self.height_mm > 0 and math.isfinite(self.height_mm)):
            raise ValueError(f"height_mm must be a positive number of mm, got {self.height_mm}")
        if self.axis not in (None, "longest", "x", "y", "z"):
            raise ValueError(f"axis must be x, y, z or longest, got {self.axis!r}")
        if self.correct and not self.max_scale >= 1:
            raise ValueError(f"max_scale must be >= 1, got {self.max_scale}")
        if self.scaling not in (None, "thin", "uniform"):
            raise ValueError(f"scaling must be 'thin' or 'uniform', got {self.scaling!r}")
