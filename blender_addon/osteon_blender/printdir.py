"""The add-on's "Print direction" (FDM build direction, docs/printing.md): which direction the
layers stack along, as a unit vector in the scene's (world) frame, and the per-vertex stress
ratio the colours show.  The axis names and the settings -> engine mapping are the wheel's
(``osteon.settings.AXES``, ``engine_arguments``).

"Up (+Z)" is the scene's +Z: the model prints as it stands in the scene, as a slicer places an
exported model; turning the object (Apply orientation) changes which of its parts face up.
"""

from __future__ import annotations

import numpy as np
from osteon.settings import AXES, axis_direction

from .errors import OsteonError

MODES = (
    ("Z", "Up (+Z)", ("Layers stack along the scene's +Z: the model prints as it stands in the "
                      "scene (as a slicer places the exported model)")),
    ("AXIS", "Chosen axis", "Layers stack along the chosen scene axis"),
    ("BEST", "Best found", ("Layers stack along the direction found by 'Find best orientation' "
                            "(the one with the lowest worst stress ratio)")),
)
AXIS_ITEMS = tuple((k, k, f"Layers stack along the scene's {k} axis") for k in AXES)

UP = (0.0, 0.0, 1.0)


def build_direction(s, orientation: dict | None = None) -> tuple:
    """The build direction (3,) of ``scene.osteon`` ``s`` (world frame, unit); ``orientation``:
    the scene's "Find best orientation" result (``state.SceneState.orientation``, passed in by
    the caller), which mode "Best found" reads."""
    mode = getattr(s, "print_direction", "Z")
    if mode == "AXIS":
        return axis_direction(s.print_axis)
    if mode == "BEST":
        found = orientation
        if found is None:
            raise OsteonError("Print direction 'Best found': press 'Find best orientation' "
                              "first")
        return tuple(float(x) for x in found["direction"])
    return UP


def colour_stress(analysis, heads_mm: np.ndarray, tails_mm: np.ndarray) -> np.ndarray:
    """Per-vertex stress (V,) MPa scaled to the in-plane allowable: ``vertex_stress`` times
    in-plane allowable / the allowable at the angle between the vertex's bone axis and the
    build direction (a bone's sections are cut across its axis), so that the colour ramp's red
    (= the in-plane allowable) means stress ratio 1; ``vertex_stress`` itself when the
    material is isotropic."""
    from osteon.orientation import layer_allowable

    x = float(analysis.allowable_stress)
    vs = np.asarray(analysis.vertex_stress, dtype=np.float64)
    r = float(getattr(analysis, "layer_strength_ratio", 1.0))
    if r == 1.0 or len(heads_mm) == 0:
        return vs
    axis = np.asarray(tails_mm, float) - np.asarray(heads_mm, float)
    n = np.linalg.norm(axis, axis=1, keepdims=True)
    axis = np.divide(axis, n, out=np.zeros_like(axis), where=n > 0)
    d = np.asarray(analysis.build_direction, float)
    d = d / np.linalg.norm(d)
    cos2 = (axis @ d) ** 2
    factor = x / layer_allowable(x, r, cos2)
    vb = np.asarray(analysis.vertex_bone)
    # no bone (< 0) reads the prepended 1.0, a bone past the list its last factor: one
    # clipped gather at bone + 1
    return vs * np.take(np.append(1.0, factor), vb + 1, mode="clip")
