"""Public Python API of osteon (README "Python", docs/method.md). Units: millimetres, newtons, MPa.

The heavy lifting happens in the C++ engine (``osteon._core``); this module checks and converts
inputs (NumPy arrays, SciPy sparse weights) and wraps the results.
"""

from __future__ import annotations

import inspect
import math
import textwrap
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import _core
from .options import (
    DEFAULT_MIN_THICKNESS,
    AnalysisOptions,
    _count,
    _min_thickness,  # noqa: F401 -- imported from here by autoskeleton
    _positive,
    _switch,
    engine_options,
    option_docs,
    section_budget,
)

__all__ = [
    "DEFAULT_MIN_THICKNESS",
    "FLAG_REASONS",
    "RESULT_FIELDS",
    "SECTION_FLAGS",
    "SECTION_KINDS",
    "Analysis",
    "AnalysisOptions",
    "Analyzer",
    "Cancelled",
    "Correction",
    "Progress",
    "Skeleton",
    "analyze",
    "correct",
    "estimate_sections",
    "section_properties",
    "shoulder_fillet_kt",
    "skin",
    "slice_section",
]

#: Raised by :func:`analyze`, :meth:`Analyzer.run` and :func:`correct` when their
#: :class:`Progress` was cancelled: no result (an :class:`Analyzer` then forgets its last run).
Cancelled = _core.Cancelled


class Progress(_core.Progress):
    """Progress and cancel switch of a long run, shared with the engine's threads.

    Pass it as ``progress=`` to :func:`analyze`, :meth:`Analyzer.run` or :func:`correct`, run
    that in a worker thread (the engine releases the GIL), and from any other thread read
    ``sections_done`` / ``sections_total`` (sections of the analysis under way whose cut is
    done / that it plans; ``sections_total`` is 0 until planned), ``runs_done`` (analyses
    finished: a correction runs one, then one per round, then a last one) and :attr:`fraction`,
    or call :meth:`cancel`: the engine checks between sections and the run raises
    :class:`Cancelled` (time to stop: one section's cut). :meth:`reset` clears it for reuse.
    """

    @property
    def fraction(self) -> float:
        """``sections_done / sections_total`` of the analysis under way, 0 before planning."""
        total = self.sections_total
        return min(1.0, self.sections_done / total) if total > 0 else 0.0

    def __repr__(self) -> str:
        state = ", cancelled" if self.cancelled else ""
        return (f"Progress({self.sections_done}/{self.sections_total} sections, "
                f"{self.runs_done} runs done{state})")


def _progress(progress: Any) -> _core.Progress | None:
    if progress is not None and not isinstance(progress, _core.Progress):
        raise ValueError(f"progress must be an osteon.Progress or None, got {progress!r}")
    return progress

#: Names of the bits of ``Analysis.section_flags``.
SECTION_FLAGS = {
    "gap_closed": _core.FLAG_GAP_CLOSED,
    "open": _core.FLAG_OPEN,
    "outside": _core.FLAG_OUTSIDE,
    "hollow": _core.FLAG_HOLLOW,
    "empty": _core.FLAG_EMPTY,
    "degenerate": _core.FLAG_DEGENERATE,
    "non_manifold": _core.FLAG_NON_MANIFOLD,
    "unreliable": _core.FLAG_UNRELIABLE,
    "too_thin": _core.FLAG_TOO_THIN,
    "junction": _core.FLAG_JUNCTION,
    "notch": _core.FLAG_NOTCH,
}

#: Plain-language reason of each flag (``Analysis.flag_reasons``, the JSON ``sections`` rows).
FLAG_REASONS = {
    "gap_closed": "the cut had open ends, joined across a small gap (mesh not closed here)",
    "open": "an open mesh edge touches this section: it may be incomplete",
    "outside": "the bone runs outside the mesh here: the section is its own part's cut",
    "hollow": "the bone runs through a hole: the wall around it is the section",
    "empty": "nothing usable was cut here: no number",
    "degenerate": "zero area or a flat section: no number",
    "non_manifold": "non-manifold edges (more than two faces on an edge) are cut here",
    "unreliable": "the bone is outside the mesh and no part here belongs to it: no number, "
                  "left out of every result",
    "too_thin": "too thin to print ({thickness} mm < {minimum} mm)",
    "junction": "a side branch is cut here: only the material that continues through the plane "
                "counts ({area} of {cut_area} mm²); where the branch is a limb rooted in a "
                "massive body this is conservative by design (docs/junctions.md)",
    "notch": "corner radius {radius} mm at {bone}: peak {peak}× the beam stress (Kt {kt}, step "
             "D/d {step}); a larger fillet or a thicker thin side lowers it",
}
#: Values of ``Analysis.section_kind``.
SECTION_KINDS = {0: "interior", 1: "joint", 2: "end"}


def _float_rows(a: Any, name: str, cols: int = 3) -> np.ndarray:
    try:
        arr = np.asarray(a)
    except (TypeError, ValueError) as exc:  # ragged lists and the like
        raise ValueError(f"{name} must be an array of shape (N, {cols}): {exc}") from None
    if arr.dtype.kind not in "fiu":
        raise ValueError(f"{name} must hold numbers, not dtype {arr.dtype}")
    if arr.ndim != 2 or arr.shape[1] != cols:
        raise ValueError(f"{name} must have shape (N, {cols}), got {arr.shape}")
    arr = np.ascontiguousarray(arr, dtype=np.float64)
    if not np.isfinite(arr).all():
        bad = int(np.argwhere(~np.isfinite(arr))[0][0])
        raise ValueError(f"{name} contain NaN or infinity (row {bad})")
    return arr


def _faces(a: Any, num_vertices: int) -> np.ndarray:
    arr = np.asarray(a)
    if arr.dtype.kind not in "iu":
        raise ValueError(f"faces must be an integer array, got dtype {arr.dtype}")
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"faces must have shape (F, 3) (triangles), got {arr.shape}")
    if arr.shape[0] == 0:
        raise ValueError("empty mesh: faces has no rows")
    lo, hi = int(arr.min()), int(arr.max())
    if lo < 0:
        raise ValueError(f"faces contain a negative vertex index ({lo})")
    if hi >= num_vertices:
        raise ValueError(
            f"face index out of range: {hi} but there are {num_vertices} vertices"
        )
    return np.ascontiguousarray(arr, dtype=np.int32)


class Skeleton:
    """A bone skeleton: ``heads`` (B,3) and ``tails`` (B,3) in mm, ``parents`` (B,) int (-1 = root).

    Several root bones are allowed (Blender rigs have IK/prop bones; TGF rigs have several bones
    leaving the root joint): the analysis holds the main root (the root whose tree carries most of
    the mesh) and joins every other root bone to the nearest bone of the main tree.
    """

    def __init__(
        self,
        heads: Any,
        tails: Any,
        parents: Any,
        names: Sequence[str] | None = None,
    ) -> None:
        self.heads = _float_rows(heads, "heads")
        self.tails = _float_rows(tails, "tails")
        p = np.asarray(parents)
        if p.ndim != 1:
            raise ValueError(f"parents must be a 1D integer array, got shape {p.shape}")
        if p.size and p.dtype.kind not in "iu":
            if p.dtype.kind == "f" and np.all(np.isfinite(p)) and np.all(p == np.round(p)):
                p = p.astype(np.int64)
            else:
                raise ValueError(f"parents must be integers, got dtype {p.dtype}")
        if len(self.heads) == 0:
            raise ValueError("skeleton has no bones")
        if not (len(self.heads) == len(self.tails) == len(p)):
            raise ValueError(
                "heads, tails and parents must have the same length "
                f"({len(self.heads)}, {len(self.tails)}, {len(p)})"
            )
        if p.size and (p.min() < -1 or p.max() >= len(p)):
            bad = int(p[(p < -1) | (p >= len(p))][0])
            raise ValueError(f"parent index {bad} out of range [-1, {len(p) - 1}]")
        self.parents = np.ascontiguousarray(p, dtype=np.int32)
        if names is None:
            names = [f"bone_{i}" for i in range(len(self.heads))]
        names = [str(n) for n in names]
        if len(names) != len(self.heads):
            raise ValueError(f"names has {len(names)} entries for {len(self.heads)} bones")
        self.names = names
        self._engine()  # checked once, here

    def _engine(self) -> _core.Skeleton:
        """The engine's (checked) copy of this skeleton; made again only if the arrays changed."""
        c = self.__dict__.get("_engine_copy")
        if c is None or not (np.array_equal(c[1], self.heads) and np.array_equal(c[2], self.tails)
                             and np.array_equal(c[3], self.parents) and c[4] == self.names):
            core = _core.Skeleton(self.heads, self.tails, self.parents, self.names)
            c = (core, np.array(self.heads), np.array(self.tails), np.array(self.parents),
                 list(self.names))
            self._engine_copy = c
        return c[0]

    @property
    def num_bones(self) -> int:
        """Number of bones B."""
        return len(self.heads)

    @property
    def lengths(self) -> np.ndarray:
        """(B,) bone lengths, mm."""
        return np.linalg.norm(self.tails - self.heads, axis=1)

    @property
    def roots(self) -> list[int]:
        """Indices of the root bones (parent -1)."""
        return [int(i) for i in np.flatnonzero(self.parents < 0)]

    def bone_index(self, bone: int | str) -> int:
        """Index of a bone given by index or name; ValueError if there is none."""
        if isinstance(bone, (int, np.integer)):
            if not 0 <= int(bone) < self.num_bones:
                raise ValueError(f"bone index {bone} out of range [0, {self.num_bones - 1}]")
            return int(bone)
        try:
            return self.names.index(str(bone))
        except ValueError:
            raise ValueError(f"no bone named {bone!r}") from None

    def scaled(self, factor: float) -> Skeleton:
        """The same skeleton with positions multiplied by ``factor`` (e.g. to mm of the print)."""
        return Skeleton(self.heads * factor, self.tails * factor, self.parents, self.names)

    def __repr__(self) -> str:
        return f"Skeleton({self.num_bones} bones, roots={self.roots})"


#: Default of ``correct(scaling=...)``: chosen by measurement, see docs/correction.md.
DEFAULT_SCALING = "thin"

def _weights_args(weights: Any, num_vertices: int, num_bones: int):
    """(dense, csr) arguments for the engine; weights: None, (V,B) array, or SciPy sparse."""
    if weights is None:
        return None, None
    if hasattr(weights, "tocsr"):  # SciPy sparse matrix or array
        if weights.shape != (num_vertices, num_bones):
            raise ValueError(
                f"weights must have shape (V, B) = ({num_vertices}, {num_bones}), "
                f"got {weights.shape}"
            )
        # Values (finite, not negative beyond solver round-off) and bone indices are checked by
        # the engine, which names the first bad entry.
        csr = weights.tocsr()
        # 32-bit bone indices (SciPy's usual type) go to the engine as they are, without a copy.
        index_type = np.int32 if csr.indices.dtype == np.int32 else np.int64
        return None, (
            np.ascontiguousarray(csr.indptr, dtype=np.int64),
            np.ascontiguousarray(csr.indices, dtype=index_type),
            np.ascontiguousarray(csr.data, dtype=np.float64),
        )
    w = np.asarray(weights)
    if w.dtype.kind not in "fiub":
        raise ValueError(f"weights must be numeric, got dtype {w.dtype}")
    if w.shape != (num_vertices, num_bones):
        raise ValueError(
            f"weights must have shape (V, B) = ({num_vertices}, {num_bones}), got {w.shape}"
        )
    return np.ascontiguousarray(w, dtype=np.float64), None  # values: checked by the engine


def _held_bone(root: int | str | None, skeleton: Skeleton) -> int:
    """The engine's held bone: -1 (the main root) or the index of ``root`` (checked already
    for its type by :class:`AnalysisOptions`) in ``skeleton``."""
    return -1 if root is None else skeleton.bone_index(root)


#: (name, shape, dtype, unit, doc) of every output of the engine, in order: the one list of
#: result fields (cpp/include/osteon/result_fields.hpp); :class:`Analysis` is made from it.
RESULT_FIELDS = tuple(_core.result_fields())

#: Result fields an :class:`Analysis` may be built without (older callers), with their default
#: (``list``: an empty list); ``Analysis.__post_init__`` fills in the ``None`` ones. The packed
#: outlines default to ``None`` (no ``keep_outlines``); every other result field is required.
_RESULT_DEFAULTS = {"section_allowable": None, "stress_ratio": None, "across_layers": None,
                    "max_stress_ratio": 0.0, "loose_pieces": list, "section_cut_area": None,
                    "section_cut_modulus": None, "section_solid_modulus": None,
                    "section_wall_area": None, "section_skin_area": None,
                    "section_infill_area": None, "nominal_stress": None,
                    "stress_concentration": None, "notch_radius": None, "notch_step": None}
_OUTLINE_SHAPES = ("(P,3)", "(L+1,)", "(S+1,)")

#: The settings an :class:`Analysis` records (fields of the same name of :class:`AnalysisOptions`).
_RECORDED_OPTIONS = ("allowable_stress", "force", "interval", "build_direction",
                     "layer_strength_ratio", "min_thickness", "print_profile")


def _field_line(name: str, shape: str, unit: str, doc: str) -> str:
    text = " ".join(part for part in (f"``{name}``", shape, unit) if part) + f": {doc}."
    return textwrap.fill(text, 96, initial_indent="- ", subsequent_indent="  ")


def _result_dataclass(cls: type) -> type:
    """``cls`` as a dataclass whose fields are :data:`RESULT_FIELDS` (required ones first), the
    recorded options, ``bone_names`` and ``thickness_pending``; its docstring lists them."""
    annotations, lines = {}, []
    rows = sorted(RESULT_FIELDS, key=lambda r: r[0] in _RESULT_DEFAULTS or r[1] in _OUTLINE_SHAPES)
    for name, shape, dtype, unit, doc in rows:
        annotations[name] = dtype if dtype in ("float", "int", "list") else "np.ndarray"
        if name in _RESULT_DEFAULTS or shape in _OUTLINE_SHAPES:
            default = _RESULT_DEFAULTS.get(name)
            setattr(cls, name, field(default_factory=list) if default is list else default)
        if dtype not in ("float", "int", "list"):
            shape = f"{shape} {dtype}"
        lines.append(_field_line(name, shape, unit, doc))
    lines.append("")
    lines += ["Settings of the run (:class:`AnalysisOptions`):", ""]
    defaults, docs = AnalysisOptions(), {n: (u, d) for n, u, d in option_docs()}
    for name in _RECORDED_OPTIONS:
        annotations[name] = {"build_direction": "np.ndarray",
                             "print_profile": "PrintProfile"}.get(name, "float")
        value = getattr(defaults, name)
        setattr(cls, name, field(default_factory=lambda v=value: np.array(v, dtype=float))
                if isinstance(value, tuple) else value)
        lines.append(_field_line(name, "(3,)" if isinstance(value, tuple) else "()", *docs[name]))
    annotations["bone_names"] = "list"
    cls.bone_names = field(default_factory=list)
    lines.append(_field_line("bone_names", "(B,)", "", "the skeleton's bone names"))
    #: the engine's regions whose thickness is not computed yet (section_thickness fills them)
    annotations["thickness_pending"] = "Any"
    cls.thickness_pending = field(default=None, repr=False, compare=False)
    cls.__annotations__ = annotations
    cls.__doc__ = (cls.__doc__.rstrip() + "\n\n" + textwrap.indent("\n".join(lines), "    ")
                   + "\n    ")
    return dataclass(cls)


@_result_dataclass
class Analysis:
    """Result of :func:`analyze`: one row per section (S), one per vertex (V). mm, N, MPa.

    Skipped sections (flag ``empty``, ``degenerate`` or ``unreliable``) have NaN modulus and
    stress and are never weak or culled; ``too_thin`` sections (thinner than ``min_thickness``
    mm) keep their stress but are never weak, culled, the maximum or corrected. The packed
    ``outline_*`` / ``cut_outline_*`` arrays are None without ``keep_outlines`` (read them as
    :attr:`section_loops` / :attr:`section_cut_loops`). ``section_thickness`` is computed on
    first read, except where the ``too_thin`` check needed it.

    Fields (cpp/include/osteon/result_fields.hpp):
    """

    @classmethod
    def _from_core(cls, d: dict, *, skeleton: Skeleton, options: AnalysisOptions) -> Analysis:
        if len(d["outline_section_start"]) == 0:  # outlines not asked for
            for name, shape, *_ in RESULT_FIELDS:
                if shape in _OUTLINE_SHAPES:
                    d[name] = None
        recorded = {name: getattr(options, name) for name in _RECORDED_OPTIONS}
        recorded["build_direction"] = np.array(options.build_direction, dtype=float)
        return cls(**d, **recorded, bone_names=list(skeleton.names))

    def __post_init__(self) -> None:
        # Results built without the layer fields (older callers): isotropic values.
        if self.section_allowable is None:
            self.section_allowable = np.full(len(self.stress), float(self.allowable_stress))
        if self.stress_ratio is None:
            self.stress_ratio = self.stress / self.section_allowable
        if self.across_layers is None:
            self.across_layers = np.zeros(len(self.stress), bool)
        if self.section_cut_area is None:
            self.section_cut_area = np.asarray(self.section_area, dtype=float).copy()
        if self.section_cut_modulus is None:
            self.section_cut_modulus = np.asarray(self.section_modulus, dtype=float).copy()
        # ... and without the printed-section fields: a solid part.
        if self.section_solid_modulus is None:
            self.section_solid_modulus = np.asarray(self.section_modulus, dtype=float).copy()
        for name in ("section_wall_area", "section_skin_area", "section_infill_area"):
            if getattr(self, name) is None:
                setattr(self, name, np.zeros(len(self.stress)))
        if self.nominal_stress is None:  # results built without the notch fields: no corner
            self.nominal_stress = np.asarray(self.stress, dtype=float).copy()
        if self.stress_concentration is None:
            self.stress_concentration = np.ones(len(self.stress))
        if self.notch_radius is None:
            self.notch_radius = np.full(len(self.stress), np.nan)
        if self.notch_step is None:
            self.notch_step = np.full(len(self.stress), np.nan)

    @property
    def num_sections(self) -> int:
        """Number of sections S."""
        return len(self.stress)

    @property
    def section_loops(self) -> list[list[np.ndarray]] | None:
        """With ``keep_outlines=True``: per section (S), the loops of the region it analysed,
        each (N,3) mm on the section plane (last point joins the first): the outer boundary
        first, then the holes; ``[]`` for a skipped section. ``None`` without outlines.
        Packed form: ``outline_points`` (P,3) mm, ``outline_loop_start`` (L+1,) and
        ``outline_section_start`` (S+1,) (section s owns loops ``[start[s], start[s+1])``)."""
        if self.outline_section_start is None:
            return None
        pts, ls, ss = self.outline_points, self.outline_loop_start, self.outline_section_start
        return [[pts[ls[k]:ls[k + 1]] for k in range(ss[s], ss[s + 1])]
                for s in range(len(ss) - 1)]

    @property
    def section_cut_loops(self) -> list[list[np.ndarray]] | None:
        """With ``keep_outlines=True``: per section (S), the loops of the whole cut of a
        ``junction`` section (before the stub was left out; :attr:`section_loops` is the core
        that was used), each (N,3) mm, outer boundary first; ``[]`` for any other section.
        ``None`` without outlines. Packed as ``cut_outline_*`` like ``outline_*``."""
        if self.cut_outline_section_start is None:
            return None
        pts, ls = self.cut_outline_points, self.cut_outline_loop_start
        ss = self.cut_outline_section_start
        return [[pts[ls[k]:ls[k + 1]] for k in range(ss[s], ss[s + 1])]
                for s in range(len(ss) - 1)]

    @property
    def infill_loops(self) -> list[list[np.ndarray]] | None:
        """With ``keep_outlines=True``: per section (S), the loops of its sparse infill (FDM) or
        hollow (resin) region (``print_profile``), each (N,3) mm on the section plane (outer
        boundaries and holes, as the orientation tells); ``[]`` where it is all solid (every
        section of a solid print). ``None`` without outlines. Packed as ``infill_outline_*``."""
        if self.infill_outline_section_start is None:
            return None
        pts, ls = self.infill_outline_points, self.infill_outline_loop_start
        ss = self.infill_outline_section_start
        return [[pts[ls[k]:ls[k + 1]] for k in range(ss[s], ss[s + 1])]
                for s in range(len(ss) - 1)]

    @property
    def junction(self) -> np.ndarray:
        """(S,) bool: sections at a junction, whose numbers are those of the core that continues
        through the plane (not the whole cut, :attr:`section_cut_area`)."""
        return (self.section_flags & SECTION_FLAGS["junction"]) != 0

    @property
    def valid(self) -> np.ndarray:
        """(S,) bool: sections that were computed (not skipped)."""
        return np.isfinite(self.stress)

    def governing_limit(self, section: int) -> str:
        """"across layers" when the layer (Z) strength governs the section's allowable, else
        "along layers" (always, for isotropic material)."""
        return "across layers" if bool(self.across_layers[section]) else "along layers"

    def flag_names(self, section: int) -> list[str]:
        """Names of the flags set on one section."""
        f = int(self.section_flags[section])
        return [name for name, bit in SECTION_FLAGS.items() if f & bit]

    def flag_reasons(self, section: int) -> list[str]:
        """Plain-language reason of each flag set on one section (see ``FLAG_REASONS``)."""
        t = float(self.section_thickness[section])
        area = float(self.section_area[section])
        cut = float(self.section_cut_area[section])
        nominal = float(self.nominal_stress[section])
        peak = float(self.stress[section]) / nominal if nominal > 0 else float("nan")
        b = int(self.section_bone[section])
        bone = (f"the {self.bone_names[b]}" if b < len(self.bone_names) and self.bone_names[b]
                else f"bone {b}")
        return [FLAG_REASONS[name].format(thickness=f"{t:.2g}", minimum=f"{self.min_thickness:g}",
                                          area=f"{area:.3g}", cut_area=f"{cut:.3g}",
                                          radius=f"{float(self.notch_radius[section]):.2g}",
                                          bone=bone, peak=f"{peak:.2g}",
                                          kt=f"{float(self.stress_concentration[section]):.2f}",
                                          step=f"{float(self.notch_step[section]):.2g}")
                for name in self.flag_names(section)]

    @property
    def notch(self) -> np.ndarray:
        """(S,) bool: sections next to a concave corner whose stress is the peak at it (Kt > 1,
        :attr:`stress_concentration`, docs/notch.md)."""
        return (self.section_flags & SECTION_FLAGS["notch"]) != 0

    @property
    def too_thin(self) -> np.ndarray:
        """(S,) bool: sections thinner than ``min_thickness`` mm (too thin to print)."""
        return (self.section_flags & SECTION_FLAGS["too_thin"]) != 0

    @property
    def unreliable(self) -> np.ndarray:
        """(S,) bool: sections no material could be tied to (bone outside the mesh)."""
        return (self.section_flags & SECTION_FLAGS["unreliable"]) != 0

    def bone_max_stress(self) -> np.ndarray:
        """(B,) largest section stress per bone, MPa (0 for bones without valid sections)."""
        out = np.zeros(len(self.bone_names))
        ok = self.valid
        np.maximum.at(out, self.section_bone[ok], self.stress[ok])
        return out

    def bone_max_ratio(self) -> tuple[np.ndarray, np.ndarray]:
        """(B,) largest stress ratio per bone (0 without valid sections) and (B,) the section
        where it occurs (-1 if none)."""
        nb = len(self.bone_names)
        out, where = np.zeros(nb), np.full(nb, -1)
        ok = np.flatnonzero(self.valid)
        order = ok[np.argsort(self.stress_ratio[ok], kind="stable")]
        for i in order:  # ascending: the last write per bone is its worst section
            out[self.section_bone[i]] = self.stress_ratio[i]
            where[self.section_bone[i]] = i
        return out, where

    def weak_bones(self) -> list[dict]:
        """Bones with a weak section, worst ratio first: ``{bone, index, max_stress_mpa, ratio,
        limit}`` (ratio = the bone's largest stress / its section's direction-dependent
        allowable; limit = "across layers" or "along layers" at that section)."""
        from .report import bone_table  # the one per-bone table

        rows = bone_table(self.section_bone, np.where(self.valid, self.stress, np.nan), self.weak,
                          self.bone_names, self.allowable_stress,
                          stress_ratio=self.stress_ratio, across_layers=self.across_layers)
        keep = ("bone", "index", "max_stress_mpa", "ratio", "limit")
        return [{k: r[k] for k in keep} for r in rows if r["weak"]]

    def summary(self) -> dict:
        """JSON-ready summary (numbers in mm, N, MPa)."""
        from .report import finite  # the one rule: non-finite -> None (JSON null)

        return {
            "max_stress_mpa": finite(self.max_stress),
            "allowable_stress_mpa": float(self.allowable_stress),
            "force_n": float(self.force),
            "interval_mm": float(self.interval),
            "max_moment_nmm": finite(self.max_moment),
            "safe_modulus_mm3": finite(self.safe_modulus),
            "held_bone": self.bone_names[self.held_bone] if self.held_bone >= 0 else None,
            "sections": int(self.num_sections),
            "weak_sections": int(self.weak.sum()),
            "culled_sections": int(self.culled.sum()),
            "skipped_sections": int((~self.valid).sum()),
            "weak_bones": self.weak_bones(),
            "max_stress_ratio": finite(self.max_stress_ratio),
            "build_direction": [float(x) for x in self.build_direction],
            "layer_strength_ratio": float(self.layer_strength_ratio),
        }

    def __getstate__(self) -> dict:
        self.section_thickness  # noqa: B018 -- fills the deferred thickness (regions don't pickle)
        return dict(self.__dict__)

    def __repr__(self) -> str:
        return (
            f"Analysis({self.num_sections} sections, max_stress={self.max_stress:.3g} MPa, "
            f"allowable={self.allowable_stress:.3g} MPa, weak={int(self.weak.sum())}, "
            f"culled={int(self.culled.sum())})"
        )


def _thickness(self: Analysis) -> np.ndarray:
    pending = self.__dict__.get("thickness_pending")
    if pending is not None:
        self.__dict__["_section_thickness"] = pending.fill(self.__dict__["_section_thickness"])
        self.__dict__["thickness_pending"] = None
    return self.__dict__["_section_thickness"]


def _set_thickness(self: Analysis, value: np.ndarray) -> None:
    self.__dict__["_section_thickness"] = value


# A property over the dataclass field: the deferred sections' thickness (mm) is computed on the
# first read, in one call into the engine.
Analysis.section_thickness = property(  # type: ignore[assignment]
    _thickness, _set_thickness,
    doc="(S,) mm: each section's thickness (cpp/src/thickness.hpp); NaN for skipped sections.")


@dataclass
class Correction:
    """Result of :func:`correct`.

    ``bone_scale`` (B,) cross-section scale per bone (with ``scaling="thin"``: the geometric mean
    sqrt(x * z) of its two axes); ``bone_scale_x``, ``bone_scale_z`` (B,) scale along each bone's
    local x and z axes (equal for both-axes scaling); ``bone_x_axis`` (B,3) unit x axis across
    each bone (z = x × bone direction, as Blender's X × Y); ``vertices`` (V,3) corrected
    positions, mm; ``rounds`` list of ``(bone index, factor, max stress after MPa, axis)`` with
    axis 0 = both axes, 1 = x only, 2 = z only; ``converged``; ``reason``; ``unfixed_sections``
    (indices into ``after``); ``max_displacement`` mm; ``volume_change_percent``; ``before`` and
    ``after`` :class:`Analysis`; ``reinforcement``: with ``reinforce_first=True`` the
    :class:`osteon.Reinforcement` of the final shape (walls and infill per region), else None.
    """

    bone_scale: np.ndarray
    bone_scale_x: np.ndarray
    bone_scale_z: np.ndarray
    bone_x_axis: np.ndarray
    vertices: np.ndarray
    rounds: list
    converged: bool
    reason: str
    unfixed_sections: list
    max_displacement: float
    volume_change_percent: float
    before: Analysis
    after: Analysis
    reinforcement: Any = None

    @property
    def num_rounds(self) -> int:
        """Number of scaling rounds taken."""
        return len(self.rounds)

    def scaled_bones(self) -> list[dict]:
        """Bones whose scale changed: ``{bone, index, scale, scale_x, scale_z}``."""
        names = self.before.bone_names
        return [
            {"bone": names[b], "index": int(b), "scale": float(self.bone_scale[b]),
             "scale_x": float(self.bone_scale_x[b]), "scale_z": float(self.bone_scale_z[b])}
            for b in np.flatnonzero(self.bone_scale != 1.0)
        ]

    def __repr__(self) -> str:
        return (
            f"Correction(converged={self.converged}, rounds={len(self.rounds)}, "
            f"max_stress {self.before.max_stress:.3g} -> {self.after.max_stress:.3g} MPa)"
        )


def _takes_options(fn):
    """Shows the :class:`AnalysisOptions` fields as keyword-only parameters in ``fn``'s
    signature (help, IDEs, ``inspect``) in place of its ``**settings``; ``fn`` receives them
    in ``settings`` and makes one checked object with ``AnalysisOptions.of(options, settings)``."""
    sig = inspect.signature(fn)
    params = [p for p in sig.parameters.values() if p.kind is not p.VAR_KEYWORD]
    params += [inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY,
                                 default=getattr(AnalysisOptions, name))
               for name, _, _ in option_docs()]
    fn.__signature__ = sig.replace(parameters=params)
    settings = "\n".join(_field_line(n, "", u, d) for n, u, d in option_docs())
    fn.__doc__ = ((fn.__doc__ or "").rstrip() + "\n\n    Settings, as keywords or ``options=``:\n\n"
                  + textwrap.indent(settings, "    ") + "\n    ")
    return fn


class Analyzer:
    """Reusable analysis of one mesh topology: faces, weights and settings fixed; call
    :meth:`run` with new vertex positions and a (posed) skeleton as often as needed (live mode).

    ``faces`` (F,3) int; ``num_vertices`` V; ``weights`` None / (V,B) / SciPy sparse; the
    settings as keywords or ``options=`` an :class:`AnalysisOptions` (kept as ``options``).
    """

    @_takes_options
    def __init__(self, faces: Any, num_vertices: int, skeleton: Skeleton, weights: Any = None, *,
                 options: AnalysisOptions | None = None, **settings: Any) -> None:
        if not isinstance(skeleton, Skeleton):
            raise ValueError("skeleton must be an osteon.Skeleton")  # noqa: TRY004
        if int(num_vertices) <= 0:
            raise ValueError("empty mesh: no vertices")
        self.num_vertices = int(num_vertices)
        self.faces = _faces(faces, self.num_vertices)
        self.options = AnalysisOptions.of(options, settings)
        dense, csr = _weights_args(weights, self.num_vertices, skeleton.num_bones)
        self._skeleton = skeleton
        core_options = engine_options(self.options, _held_bone(self.options.root, skeleton))
        self._core = _core.Analyzer(self.faces, self.num_vertices, skeleton.num_bones, dense, csr,
                                    core_options)

    # the settings by name (public attributes before the options object), read-only views
    force = property(lambda self: self.options.force)
    allowable_stress = property(lambda self: self.options.allowable_stress)
    interval = property(lambda self: self.options.interval)
    layer_strength_ratio = property(lambda self: self.options.layer_strength_ratio)
    min_thickness = property(lambda self: self.options.min_thickness)
    build_direction = property(lambda self: np.array(self.options.build_direction, dtype=float))

    def run(self, vertices: Any, skeleton: Skeleton | None = None, *,
            progress: Progress | None = None) -> Analysis:
        """Analyse ``vertices`` (V,3) mm with ``skeleton`` (default: the one given at creation).
        ``progress``: a :class:`Progress` to follow or cancel the run from another thread
        (raises :class:`Cancelled`)."""
        progress = _progress(progress)
        sk = self._skeleton if skeleton is None else skeleton
        if not isinstance(sk, Skeleton):
            raise ValueError("skeleton must be an osteon.Skeleton")  # noqa: TRY004
        if sk.num_bones != self._skeleton.num_bones:
            raise ValueError(
                f"skeleton has {sk.num_bones} bones, the analyzer was built for "
                f"{self._skeleton.num_bones}"
            )
        return self._run_rows(_float_rows(vertices, "vertices"), sk, progress)

    def _run_rows(self, v: np.ndarray, sk: Skeleton, progress: Progress | None, *,
                  keep_for_next_run: bool = True) -> Analysis:
        """`run` once ``v`` is checked (``_float_rows``: float64, contiguous, finite);
        ``keep_for_next_run=False``: a one-off run (the engine keeps no copy of the inputs for a
        partial re-run: 18 MB of fresh pages on 1.5M faces)."""
        if len(v) != self.num_vertices:
            raise ValueError(
                f"vertices has {len(v)} rows, the analyzer was built for {self.num_vertices}"
            )
        check_section_budget(sk, v, self.options)
        d = self._core.run(v, sk._engine(), progress, keep_for_next_run=keep_for_next_run)
        return Analysis._from_core(d, skeleton=sk, options=self.options)


@_takes_options
def analyze(vertices: Any, faces: Any, skeleton: Skeleton, weights: Any = None, *,
            options: AnalysisOptions | None = None, progress: Progress | None = None,
            **settings: Any) -> Analysis:
    """Skeleton-sectional stress analysis of a mesh.

    ``vertices`` (V,3) mm, ``faces`` (F,3) int, ``skeleton`` :class:`Skeleton` (mm), ``weights``
    None (each vertex bound to its nearest bone) or (V,B) dense / SciPy sparse. The settings
    (listed below) as keywords, e.g. ``force=20.0``, or as ``options=`` an
    :class:`AnalysisOptions` (not both; equal settings give bit-identical results). With a
    ``build_direction`` and ``layer_strength_ratio`` each section's allowable depends on the
    angle between its normal and the build direction (``section_allowable``, ``stress_ratio``,
    ``across_layers``; docs/printing.md). ``progress``: a :class:`Progress` to follow the run
    from another thread or cancel it (then :class:`Cancelled` is raised);
    :func:`estimate_sections` tells the section count beforehand. Raises ValueError on bad
    input.
    """
    progress = _progress(progress)
    v = _float_rows(vertices, "vertices")
    if len(v) == 0:
        raise ValueError("empty mesh: vertices has no rows")
    analyzer = Analyzer(faces, len(v), skeleton, weights,
                        options=AnalysisOptions.of(options, settings))
    # The vertices were checked above: one finite pass over them, not two (~2-6 ms at 750k).
    return analyzer._run_rows(v, skeleton, progress, keep_for_next_run=False)


#: ``correct(..., reinforce_first=True)``: :func:`osteon.reinforcement.reinforce_then_correct`,
#: put here by that module when it is imported (``import osteon`` does), so that this module
#: imports nothing of it (no import cycle: the reinforcement builds on this module).
_REINFORCE_FIRST: list = []


@_takes_options
def correct(
    vertices: Any,
    faces: Any,
    skeleton: Skeleton,
    weights: Any,
    *,
    max_scale: float = 3.0,
    max_rounds: int = 100,
    target_ratio: float = 0.99,
    scaling: str = DEFAULT_SCALING,
    flat_aspect: float = 2.0,
    bone_x_axes: Any = None,
    bone_long_axes: Any = None,
    options: AnalysisOptions | None = None,
    progress: Progress | None = None,
    reinforce_first: bool = False,
    **settings: Any,
) -> Correction:
    """Thicken weak bones (paper §5) until no section is weak, or a stop rule ends the loop.

    Each round scales the cross-section of the bone whose domain holds the weakest section by
    ``cbrt(stress / (target_ratio * allowable_stress))`` (capped at ``max_scale`` per bone) and
    re-skins the rest mesh (linear blend skinning, weights normalised per vertex). ``weights``
    (V,B) dense or SciPy sparse is required (None binds each vertex to its nearest bone).

    ``scaling="uniform"`` scales both axes across the bone (the paper). ``scaling="thin"``
    thickens a flat section (width / thickness >= ``flat_aspect``) across its thickness only,
    by ``sqrt(stress / target)`` (a plate's W grows as t²), along the bone's local x or z axis
    nearest to it (round sections still get both axes). ``bone_x_axes`` (B,3) gives each bone's
    local x axis (e.g. Blender's, so that pose-bone scale X/Z reproduce the result); None lets
    each bone's axes follow the first flat section scaled on it. ``bone_long_axes`` (B,3): the
    axis each bone scales across (kept at scale 1), None: its segment. A joint rig imported into
    Blender (FBX/glTF) has bones whose local Y is not the segment analysed; scaling across the
    bone's own local axis nearest the segment is what Blender's pose scale can reproduce exactly
    (the sections stay perpendicular to the segments: every round re-analyses the scaled mesh,
    so this changes how the bone is thickened, not what is checked). The analysis settings
    (keywords or ``options=``) as in :func:`analyze`: the loop is driven by the stress ratio
    against each section's direction-dependent allowable (``build_direction``,
    ``layer_strength_ratio``), by the junction cores with ``junctions=True``; with
    ``keep_outlines`` ``before`` and ``after`` carry their sections' loops
    (:attr:`Analysis.section_loops`).
    ``progress``: a :class:`Progress` (``runs_done`` counts the analyses: the first, one per
    round, the last) to follow or cancel the loop (:class:`Cancelled`) from another thread.
    With a ``print_profile`` the loop is driven by the printed sections.
    ``reinforce_first`` (with an FDM ``print_profile``): reinforce first (more walls, denser
    infill where weak: :func:`osteon.reinforce`) and thicken only what even solid cannot carry;
    the result's ``reinforcement`` has the regions (docs/correction.md).
    """
    if _switch(reinforce_first, "reinforce_first"):
        opts = AnalysisOptions.of(options, settings)
        analysis = {name: getattr(opts, name) for name, _, _ in option_docs()}
        profile = analysis.pop("print_profile", None)
        return _REINFORCE_FIRST[0](
            vertices, faces, skeleton, weights, print_profile=profile, max_scale=max_scale,
            max_rounds=max_rounds, target_ratio=target_ratio, scaling=scaling,
            flat_aspect=flat_aspect, bone_x_axes=bone_x_axes, bone_long_axes=bone_long_axes,
            progress=progress, **analysis)
    progress = _progress(progress)
    if scaling not in ("uniform", "thin"):
        raise ValueError(f"scaling must be 'uniform' or 'thin', got {scaling!r}")
    if not (float(flat_aspect) >= 1.0):
        raise ValueError(f"flat_aspect must be >= 1, got {flat_aspect!r}")
    axes = None
    if bone_x_axes is not None:
        axes = _float_rows(bone_x_axes, "bone_x_axes")
        if len(axes) != skeleton.num_bones:
            raise ValueError(
                f"bone_x_axes must have shape ({skeleton.num_bones}, 3), got {axes.shape}"
            )
    if not isinstance(skeleton, Skeleton):
        raise ValueError("skeleton must be an osteon.Skeleton")  # noqa: TRY004
    long_axes = _long_axes(bone_long_axes, skeleton.num_bones)
    v = _float_rows(vertices, "vertices")
    if len(v) == 0:
        raise ValueError("empty mesh: vertices has no rows")
    f = _faces(faces, len(v))
    options = AnalysisOptions.of(options, settings)
    check_section_budget(skeleton, v, options)
    if not (float(max_scale) >= 1.0 and math.isfinite(float(max_scale))):
        raise ValueError(f"max_scale must be a finite number >= 1, got {max_scale!r}")
    max_rounds = _count(max_rounds, "max_rounds")
    if weights is None:
        from scipy import sparse

        o = options  # each vertex bound to its nearest bone (the settings as before)
        nearest = analyze(v, f, skeleton, None, force=o.force, allowable_stress=o.allowable_stress,
                          interval=o.interval, root=o.root, progress=progress,
                          junctions=o.junctions).vertex_bone
        weights = sparse.csr_matrix(
            (np.ones(len(v)), (np.arange(len(v)), nearest)), shape=(len(v), skeleton.num_bones)
        )
    dense, csr = _weights_args(weights, len(v), skeleton.num_bones)
    core_options = engine_options(options, _held_bone(options.root, skeleton))
    co = _core.CorrectionOptions()
    co.max_scale, co.max_rounds = float(max_scale), max_rounds
    co.target_ratio, co.thin_direction = float(target_ratio), scaling == "thin"
    co.flat_aspect, co.bone_x_axes = float(flat_aspect), axes
    co.bone_long_axes = long_axes
    d = _core.correct(v, f, skeleton._engine(), dense, csr, core_options, co, progress)
    d["before"] = Analysis._from_core(d["before"], skeleton=skeleton, options=options)
    d["after"] = Analysis._from_core(d["after"], skeleton=skeleton, options=options)
    return Correction(**d)


def shoulder_fillet_kt(big_diameter: float, small_diameter: float, radius: float) -> float:
    """Kt of a stepped round bar's shoulder fillet in bending: big and small diameter D > d and
    fillet radius r, mm: the larger of Roark's Formulas 7th ed. Table 17.1 (the fit of Peterson's
    photoelastic charts; clamped on the safe side outside 0.25 <= h/r <= 20) and the
    finite-element fit of Tipton, Sorem & Rolovic (ASME J. Mech. Design 118, 1996), which reads
    higher at sharp fillets; D/d capped at 3 (docs/notch.md, "Kt"). 1 when D <= d. Raises
    ValueError for a non-positive or non-finite length."""
    big = _positive(big_diameter, "big_diameter", "mm")
    small = _positive(small_diameter, "small_diameter", "mm")
    r = _positive(radius, "radius", "mm")
    return float(_core.shoulder_fillet_kt(big, small, r))


def check_section_budget(skeleton: Skeleton, vertices: np.ndarray,
                         options: AnalysisOptions) -> None:
    """The global budget (``options.max_sections``), checked before any work: ValueError with
    the estimate of sections and memory (:func:`osteon.options.section_budget`) when the
    whole model would make more sections. The count is exact and takes microseconds."""
    n = int(_core.count_sections(skeleton._engine(), options.interval))
    if n <= options.max_sections:
        return
    size = float(np.max(vertices.max(axis=0) - vertices.min(axis=0))) if len(vertices) else 0.0
    over = section_budget(n, len(vertices), options.interval, size, options.max_sections,
                          setting="max_sections")
    raise ValueError(f"refused: {over}")


def estimate_sections(skeleton: Skeleton, interval: float = 2.0) -> int:
    """Number of sections :func:`analyze` makes for ``skeleton`` (mm) at ``interval`` mm,
    computed from the bones alone (no mesh, no cut; microseconds): per bone ``ceil(L / h) - 1``
    interior planes, one section per free bone end and one per pair of bones meeting at a joint.
    Exact: it equals ``Analysis.num_sections`` of any mesh and held bone. Use it to catch a
    setting that would make millions of sections (a model in metres taken as mm, a tiny
    interval) before starting; :func:`osteon.settings.section_guard` words the warning."""
    if not isinstance(skeleton, Skeleton):
        raise ValueError("skeleton must be an osteon.Skeleton")  # noqa: TRY004
    return int(_core.count_sections(skeleton._engine(), _positive(interval, "interval", "mm")))


def _long_axes(value, n_bones: int):
    """(B,3) float rows of ``bone_long_axes`` (finite, non-zero), or None."""
    if value is None:
        return None
    axes = _float_rows(value, "bone_long_axes")
    if len(axes) != n_bones:
        raise ValueError(f"bone_long_axes must have shape ({n_bones}, 3), got {axes.shape}")
    if not (np.linalg.norm(axes, axis=1) > 1e-9).all():
        raise ValueError("bone_long_axes must be non-zero vectors (the axis a bone scales across)")
    return axes


def skin(vertices: Any, skeleton: Skeleton, weights: Any, bone_scale: Any, *,
         bone_scale_z: Any = None, bone_x_axes: Any = None,
         bone_long_axes: Any = None) -> np.ndarray:
    """Linear blend skinning of rest ``vertices`` (V,3) mm with per-bone cross-section scales
    ``bone_scale`` (B,): each bone scales the two axes across itself about its own axis. With
    ``bone_scale_z`` (B,) and ``bone_x_axes`` (B,3), ``bone_scale`` applies along each bone's x
    axis and ``bone_scale_z`` along z = x × direction (as :class:`Correction` reports them).
    ``bone_long_axes`` (B,3): each bone scales across this axis through its head instead of its
    segment (x is then made perpendicular to it and z = x × long; see :func:`correct`)."""
    v = _float_rows(vertices, "vertices")
    dense, csr = _weights_args(weights, len(v), skeleton.num_bones)
    if dense is None and csr is None:
        raise ValueError("skin() needs weights")
    scales = []
    for name, value in (("bone_scale", bone_scale), ("bone_scale_z", bone_scale_z)):
        if value is None:
            scales.append(None)
            continue
        s = np.asarray(value, dtype=np.float64)
        if s.shape != (skeleton.num_bones,):
            raise ValueError(f"{name} must have shape ({skeleton.num_bones},), got {s.shape}")
        if not np.isfinite(s).all() or (s <= 0).any():
            raise ValueError(f"{name} must be positive and finite")
        scales.append(list(s))
    axes = None
    if bone_scale_z is not None:
        if bone_x_axes is None:
            raise ValueError("bone_scale_z needs bone_x_axes (B,3): the axes it scales along")
        axes = _float_rows(bone_x_axes, "bone_x_axes")
    long_axes = _long_axes(bone_long_axes, skeleton.num_bones)
    return _core.skin(v, skeleton._engine(), dense, csr, scales[0], scales[1], axes, long_axes)


def section_properties(outer: Any, holes: Sequence[Any] = ()) -> dict:
    """Exact properties of a polygon with holes (2D, mm): ``area`` mm², ``centroid``,
    ``second_moment`` (Juu, Juv, Jvv) mm⁴ about the centroid, ``modulus`` (minimum section
    modulus over all bending directions) mm³, ``valid``."""
    return _core.section_properties(
        _float_rows(outer, "outer", 2), [_float_rows(h, "hole", 2) for h in holes]
    )


def slice_section(vertices: Any, faces: Any, origin: Any, normal: Any,
                  gap_tolerance: float = 0.0) -> dict:
    """The section of the mesh by the plane (origin, normal) around ``origin``: ``outer`` (N,3)
    and ``holes`` (list of (M,3)) loops in mm, ``found``, ``flags``."""
    v = _float_rows(vertices, "vertices")
    f = _faces(faces, len(v))
    o = np.asarray(origin, dtype=float).ravel()
    n = np.asarray(normal, dtype=float).ravel()
    if (o.shape != (3,) or n.shape != (3,) or not np.isfinite(o).all()
            or not np.isfinite(n).all() or not np.linalg.norm(n) > 0):
        raise ValueError("origin and normal must be finite 3-vectors, normal non-zero")
    return _core.slice_section(v, f, list(o), list(n), float(gap_tolerance))
