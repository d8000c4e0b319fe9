"""What the add-on remembers about each scene, in one object per scene.

``SceneState`` holds the operators' last result, the vertex-group weight cache, the live
session (at most one in all scenes) with the readout it leaves behind, and the overlay's
outlines.  The service module, live mode and the overlay read and write these fields instead
of keeping dicts of their own keyed by scene.  Nothing is stored in the .blend: the state
lives as long as the add-on is registered (``clear`` on unregister).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field

from . import bridge


@dataclass
class SceneState:
    #: the operators' last result: ``{"report", "analysis", "inputs", "correction"}``
    last: dict | None = None
    #: the result the panel shows (summary, rows, row clicks): the operators' ``last`` or, once
    #: Live has updated, Live's latest in the same form (``results.show`` sets it)
    shown: dict | None = None
    #: vertex-group weights read once and reused while the mesh and groups are unchanged
    weights: bridge.WeightCache = field(default_factory=bridge.WeightCache)
    #: the running live session (``live.Session``) of this scene, if any
    live: object | None = None
    #: the readout a stopped (or failed) live session left for the sidebar
    live_readout: object | None = None
    #: ``(analysis, overlay.Outlines)`` the overlay draws
    outlines: tuple | None = None
    #: the operator analysis (``last["analysis"]``) the overlay has already outlined
    outlined_last: object | None = None
    #: the bone the result list shows (ops/select_bone.weakest_section: its segment and
    #: weakest section, world space), drawn in yellow by the overlay
    highlight: dict | None = None
    #: "Find best orientation": ``{"object", "direction" (3,) world, "result"
    #: (osteon.Orientation), "before", "applied", "matrices" (name -> matrix_world before
    #: Apply), "preview" (name of the arrow empty)}`` (ops/orientation.py)
    orientation: dict | None = None
    #: "Export for slicer (3MF)": ``{"object", "result" (osteon.Reinforcement)}`` between the
    #: modifiers shown and the file written (ops/slicer_export.py)
    slicer_export: dict | None = None
    #: the last analysis' loose pieces (shells that would fall off the print): ``{"object"
    #: (name of the analysed mesh), "vertices" (its vertex count then), "pieces" (list of (n,)
    #: int64 vertex-index arrays)}``, read by ``osteon.select_loose_pieces`` (ops/loose.py)
    loose_pieces: dict | None = None


_STATES: dict[str, SceneState] = {}


def _name(scene) -> str:
    return scene if isinstance(scene, str) else scene.name


def of(scene) -> SceneState:
    """The state of a scene (object or name), created on first use."""
    return _STATES.setdefault(_name(scene), SceneState())


def get(scene) -> SceneState | None:
    """The state of a scene if it has one (never creates)."""
    return _STATES.get(_name(scene))


def live_session():
    """The one running live session, whichever scene it watches (or None)."""
    return next((s.live for s in _STATES.values() if s.live is not None), None)


def all_states() -> list[SceneState]:
    return list(_STATES.values())


def clear() -> None:
    """Forget every scene's state (unregister)."""
    for s in _STATES.values():
        s.weights.clear()
    _STATES.clear()


class _LastResults(Mapping):
    """Read-only ``scene name -> last operator result`` view (``service.LAST``)."""

    def __getitem__(self, scene_name: str) -> dict:
        s = _STATES.get(scene_name)
        if s is None or s.last is None:
            raise KeyError(scene_name)
        return s.last

    def __iter__(self) -> Iterator[str]:
        return (k for k, s in list(_STATES.items()) if s.last is not None)

    def __len__(self) -> int:
        return sum(1 for s in _STATES.values() if s.last is not None)


LAST = _LastResults()
