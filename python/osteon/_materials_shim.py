"""Material lookup for the batch until ``osteon/materials.py`` (issue 15) lands; then the batch
imports that module and this file goes away."""

from __future__ import annotations

import math


def material_strength(name: str, strength_mpa: float | None) -> tuple[str, float]:
    """(material name, strength in MPa) from a preset name or an explicit strength."""
    from .cli import MATERIALS

    if strength_mpa is not None:
        strength, material = float(strength_mpa), "custom"
    else:
        key = {k.lower(): k for k in MATERIALS}.get(str(name).lower())
        if key is None:
            raise ValueError(
                f"unknown material {name!r}; choose one of {', '.join(MATERIALS)} "
                "or give a strength in MPa"
            )
        strength, material = MATERIALS[key], key
    if not (strength > 0 and math.isfinite(strength)):
        raise ValueError(f"strength must be a positive number of MPa, got {strength}")
    return material, strength
