"""Viewport overlay: the section outlines of the last analysis, coloured by stress ratio.

By default only the weak sections (over the limit), the doubtful ones (a suspect cut,
``osteon.doubt``) and the corner sections (a stress concentration at a fillet or step,
docs/notch.md) are drawn, so that the colours on the surface stay visible; the live
settings' "All sections" adds every other outline, thin and half transparent.  The bone the
result list shows (``ops/select_bone``) is drawn in yellow with its weakest section.

The outlines are computed OUTSIDE the draw callback, right after an analysis (by the live
mode, or once after the Analyze button when the overlay is on), as world-space line
segments in NumPy arrays; the draw callback only uploads them once per new result and
draws them with the ``gpu`` module (no ``bgl``).  Weak sections (stress > allowable) are
drawn thick and magenta-red, culled (surely safe) ones dark grey, the others blue -> red
by stress / allowable like the ``osteon_stress`` colour layer (darkened so that the lines
stand out on the coloured surface).  Lines are drawn without depth test (X-ray like).
At a junction (a side branch cut, docs/junctions.md) the outline is the core that was
analysed, and the whole cut is drawn dimmer and dashed around it.

Nothing is drawn, and no draw handler is ever added, in background mode.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import bpy
import numpy as np

from . import core, state

WIDTH = 1.0        # px, ordinary sections (only with "All sections")
WEAK_WIDTH = 3.0   # px, weak sections
DOUBT_WIDTH = 2.0  # px, doubtful sections
HIGHLIGHT_WIDTH = 4.0  # px, the shown bone and its weakest section
WEAK_RGBA = (1.0, 0.0, 0.75, 1.0)      # magenta-red: stands out on the red (weak) surface
DOUBT_RGBA = (1.0, 0.55, 0.0, 0.9)     # orange: a suspect cut
HIGHLIGHT_RGBA = (1.0, 0.9, 0.1, 1.0)  # yellow: the bone shown from the result list
NOTCH_WIDTH = 2.0  # px, corner sections (a stress concentration, issue 33)
NOTCH_RGBA = (1.0, 1.0, 1.0, 0.9)      # white: on none of the stress colours
CULLED_RGBA = (0.25, 0.25, 0.25, 0.5)
SHADE = 0.55   # ordinary outlines: the stress colour darkened, to stand out on the surface
ALPHA = 0.5    # ordinary outlines: half transparent over the colours
CUT_WIDTH = 1.0   # px, the whole cut of a junction section (dashed, dimmer)
CUT_ALPHA = 0.45
INFILL_WIDTH = 1.0   # px, the sparse-infill region inside a printed section's outline
INFILL_ALPHA = 0.6

_versions = itertools.count(1)


@dataclass
class Outlines:
    """World-space segments (pairs of rows, for a LINES batch) of the section outlines."""

    lines: np.ndarray          # (2N, 3) float32, ordinary sections
    colors: np.ndarray         # (2N, 4) float32
    weak_lines: np.ndarray     # (2M, 3) float32, weak sections
    weak_colors: np.ndarray    # (2M, 4) float32
    section_ids: np.ndarray    # (K,) int, sections that got an outline
    weak_ids: np.ndarray       # (k,) int, weak sections among them
    #: (2D, 3) float32 segments of the doubtful sections that are not weak (also in ``lines``)
    doubt_lines: np.ndarray = field(default_factory=lambda: np.empty((0, 3), np.float32))
    version: int = field(default_factory=lambda: next(_versions))
    #: (2C, 3) float32 segments of the corner sections (Kt > 1) that are not weak: where a
    #: corner raises the stress (the weak ones are drawn as weak)
    notch_lines: np.ndarray = field(default_factory=lambda: np.empty((0, 3), np.float32))
    # the whole cut of junction sections: every other segment (dashed), dimmer
    cut_lines: np.ndarray = field(default_factory=lambda: np.empty((0, 3), np.float32))
    cut_colors: np.ndarray = field(default_factory=lambda: np.empty((0, 4), np.float32))
    # the sparse-infill region of printed sections (a print profile, docs/printing.md): its
    # loops inside the outline, thinner; those of weak sections drawn always, the rest with
    # "All sections"
    infill_lines: np.ndarray = field(default_factory=lambda: np.empty((0, 3), np.float32))
    infill_colors: np.ndarray = field(default_factory=lambda: np.empty((0, 4), np.float32))
    weak_infill_lines: np.ndarray = field(default_factory=lambda: np.empty((0, 3), np.float32))

    @property
    def num_sections(self) -> int:
        return len(self.section_ids)


# --------------------------------------------------------------------------- geometry (no bpy)


def compute_outlines(analysis, mm_per_unit: float = 1.0) -> Outlines:
    """Outline of every computed section of ``analysis`` (an ``osteon.Analysis`` made with
    ``keep_outlines=True``), in world space (Blender units = mm / ``mm_per_unit``).

    The loops are the ones the engine analysed (``outline_points`` / ``outline_loop_start`` /
    ``outline_section_start``): nothing is cut again here.  Without them (an analysis made
    without ``keep_outlines``) there is nothing to draw.  Pure NumPy: safe to run in a worker
    thread."""
    k = np.float32(mm_per_unit)
    empty3, empty4 = np.empty((0, 3), np.float32), np.empty((0, 4), np.float32)
    ss = getattr(analysis, "outline_section_start", None)
    if ss is None or len(ss) < 2:
        none = np.empty(0, dtype=np.int64)
        return Outlines(lines=empty3, colors=empty4, weak_lines=empty3, weak_colors=empty4,
                        section_ids=none, weak_ids=none)
    pts = np.asarray(analysis.outline_points, dtype=np.float64)
    ls = np.asarray(analysis.outline_loop_start, dtype=np.int64)
    ss = np.asarray(ss, dtype=np.int64)
    # Segment p -> next point of its loop (the last point joins the first).
    nxt = np.arange(1, len(pts) + 1)
    nxt[ls[1:] - 1] = ls[:-1]
    loop_section = np.repeat(np.arange(len(ss) - 1), np.diff(ss))
    point_section = np.repeat(loop_section, np.diff(ls))
    stress = np.asarray(analysis.stress, dtype=np.float64)
    ratio = stress / float(analysis.allowable_stress)
    culled = np.asarray(analysis.culled, dtype=bool)
    weak = np.asarray(analysis.weak, dtype=bool)
    rgba = np.full((len(stress), 4), ALPHA, dtype=np.float32)
    rgba[:, :3] = SHADE * core.ramp(ratio)
    rgba[culled] = CULLED_RGBA

    def lines_of(mask):
        sel = np.flatnonzero(mask[point_section])
        seg = np.empty((2 * len(sel), 3), dtype=np.float32)
        seg[0::2] = pts[sel]
        seg[1::2] = pts[nxt[sel]]
        return seg / k, sel

    outlined = np.diff(ss) > 0
    lines, sel = lines_of(outlined & ~weak)
    colors = np.repeat(rgba[point_section[sel]], 2, axis=0)
    weak_lines, _ = lines_of(outlined & weak)
    weak_colors = np.broadcast_to(np.float32(WEAK_RGBA), (len(weak_lines), 4)).copy()
    doubt_lines, _ = lines_of(outlined & ~weak & doubtful_sections(analysis, len(stress)))
    notch_lines, _ = lines_of(outlined & ~weak & notch_sections(analysis, len(stress)))
    cut_lines, cut_colors = _dashed_cuts(analysis, rgba, k)
    infill_lines, infill_colors = _infill_loops(analysis, rgba, k, ~weak)
    weak_infill_lines, _ = _infill_loops(analysis, rgba, k, weak)
    return Outlines(infill_lines=infill_lines, infill_colors=infill_colors,
                    weak_infill_lines=weak_infill_lines,lines=np.ascontiguousarray(lines), colors=np.ascontiguousarray(colors),
                    weak_lines=np.ascontiguousarray(weak_lines), weak_colors=weak_colors,
                    section_ids=np.flatnonzero(outlined).astype(np.int64),
                    weak_ids=np.flatnonzero(outlined & weak).astype(np.int64),
                    doubt_lines=np.ascontiguousarray(doubt_lines),
                    notch_lines=np.ascontiguousarray(notch_lines),
                    cut_lines=cut_lines, cut_colors=cut_colors)


def doubtful_sections(analysis, n: int) -> np.ndarray:
    """(n,) bool: sections with a stress but a suspect cut (``osteon.doubt``); all False when
    the engine's Python package or the flags are not there."""
    try:
        from osteon.doubt import section_doubt

        d = np.asarray(section_doubt(analysis)["doubtful"], dtype=bool)
    except Exception:  # noqa: BLE001 -- a drawing aid: no doubt outlines rather than no overlay
        return np.zeros(n, dtype=bool)
    return d if d.shape == (n,) else np.zeros(n, dtype=bool)


def notch_sections(analysis, n: int) -> np.ndarray:
    """(n,) bool: sections whose stress a corner raises (``stress_concentration`` > 1);
    all False for a result without the corner fields."""
    kt = getattr(analysis, "stress_concentration", None)
    if kt is None:
        return np.zeros(n, dtype=bool)
    kt = np.asarray(kt, dtype=np.float64)
    return kt > 1.0 if kt.shape == (n,) else np.zeros(n, dtype=bool)


def highlight_lines(where: dict) -> np.ndarray:
    """(2H, 3) float32 LINES segments of a shown bone (``ops/select_bone.weakest_section``):
    its segment and its weakest section's outline loops, world space."""
    segs = [np.asarray(where["bone"], dtype=np.float32)]
    for loop in where["loops"]:
        p = np.asarray(loop, dtype=np.float32)
        seg = np.empty((2 * len(p), 3), dtype=np.float32)
        seg[0::2] = p
        seg[1::2] = np.roll(p, -1, axis=0)
        segs.append(seg)
    return np.ascontiguousarray(np.concatenate(segs))


def _packed_loops(analysis, prefix: str):
    """(points (P,3), next point of each point's loop (P,), loop start of each point (P,),
    section of each point (P,)) of loops packed like ``outline_*`` under ``prefix``
    (``cut_outline``, ``infill_outline``); None when the analysis has none."""
    ss = getattr(analysis, f"{prefix}_section_start", None)
    if ss is None or len(ss) < 2 or ss[-1] == 0:
        return None
    pts = np.asarray(getattr(analysis, f"{prefix}_points"), dtype=np.float64)
    ls = np.asarray(getattr(analysis, f"{prefix}_loop_start"), dtype=np.int64)
    nxt = np.arange(1, len(pts) + 1)
    nxt[ls[1:] - 1] = ls[:-1]
    loop_of = np.repeat(np.arange(len(ls) - 1), np.diff(ls))
    section_of = np.repeat(np.repeat(np.arange(len(ss) - 1), np.diff(ss)), np.diff(ls))
    return pts, nxt, ls[loop_of], section_of


def _loop_segments(packed, sel, rgba, alpha, k):
    """LINES segments from the points ``sel`` of ``packed`` to their next ones, in their
    section's colour at ``alpha``, world space."""
    pts, nxt, _first, section_of = packed
    seg = np.empty((2 * len(sel), 3), dtype=np.float32)
    seg[0::2], seg[1::2] = pts[sel], pts[nxt[sel]]
    colors = np.repeat(rgba[section_of[sel]], 2, axis=0)
    colors[:, 3] = alpha
    return np.ascontiguousarray(seg / k), np.ascontiguousarray(colors)


def _dashed_cuts(analysis, rgba, k):
    """Every other segment of the whole-cut loops of junction sections (``cut_outline_*``),
    in the section's colour at CUT_ALPHA."""
    packed = _packed_loops(analysis, "cut_outline")
    if packed is None:
        return np.empty((0, 3), np.float32), np.empty((0, 4), np.float32)
    sel = np.flatnonzero((np.arange(len(packed[0])) - packed[2]) % 2 == 0)
    return _loop_segments(packed, sel, rgba, CUT_ALPHA, k)


def _infill_loops(analysis, rgba, k, sections):
    """Segments and colours (INFILL_ALPHA) of the sparse-infill loops of printed sections
    (``infill_outline_*``, a print profile) among the ``sections`` (S,) bool mask; empty
    without them."""
    packed = _packed_loops(analysis, "infill_outline")
    if packed is None:
        return np.empty((0, 3), np.float32), np.empty((0, 4), np.float32)
    sel = np.flatnonzero(np.asarray(sections, dtype=bool)[packed[3]])
    return _loop_segments(packed, sel, rgba, INFILL_ALPHA, k)


# --------------------------------------------------------------------------- state

# per scene (state.SceneState): ``outlines`` = (the analysis outlined, Outlines) and
# ``outlined_last`` = the operator result's analysis already looked at
_handle = None
_batches: dict = {"version": None}
_pending_refresh: set = set()


def set_outlines(scene_name: str, analysis, outlines: Outlines | None) -> None:
    state.of(scene_name).outlines = None if outlines is None else (analysis, outlines)
    bridge_redraw()


def get_outlines(scene_name: str) -> Outlines | None:
    st = state.get(scene_name)
    return st.outlines[1] if st is not None and st.outlines else None


def set_highlight(scene, where: dict | None) -> None:
    """Show (``where`` from ``ops/select_bone.weakest_section``) or forget the highlighted
    bone; the draw handler is on while a bone is shown (UI only)."""
    st = state.of(scene)
    if where is None:
        st.highlight = None
    else:
        st.highlight = dict(where, lines=highlight_lines(where), version=next(_versions))
    if not bpy.app.background:
        sync(scene if not isinstance(scene, str) else bpy.data.scenes.get(scene))
        bridge_redraw()


def clear() -> None:
    for st in state.all_states():
        st.outlines = st.outlined_last = st.highlight = None
    _pending_refresh.clear()
    _batches.clear()
    _batches["version"] = None


def bridge_redraw() -> None:
    if not bpy.app.background:
        from . import bridge

        bridge.tag_redraw_view3d(("WINDOW",))


def refresh_from_last(scene_name: str):
    """Outlines of the Analyze/Correct operators' last result (the scene state's ``last``)."""
    _pending_refresh.discard(scene_name)
    st = state.get(scene_name)
    entry = st.last if st is not None else None
    if not entry:
        return
    analysis, inp = entry["analysis"], entry["inputs"]
    st.outlined_last = analysis
    try:
        out = compute_outlines(analysis, inp.mm_per_unit)
    except Exception as e:  # noqa: BLE001 -- a drawing aid must never break the UI
        print(f"osteon overlay: no outlines ({type(e).__name__}: {e})")
        return
    set_outlines(scene_name, analysis, out)
    return  # one-shot timer


# --------------------------------------------------------------------------- drawing (UI only)

_SHADER_NAMES = {
    # 4.x names first, then the 3.x ones
    "polyline": ("POLYLINE_SMOOTH_COLOR", "3D_POLYLINE_SMOOTH_COLOR"),
    "smooth": ("SMOOTH_COLOR", "3D_SMOOTH_COLOR"),
}


def builtin_shader(kind: str):
    """(shader, name) of a built-in shader, trying the Blender 4.x then the 3.x name."""
    import gpu

    names = _SHADER_NAMES[kind]
    if bpy.app.version < (4, 0, 0):
        names = names[::-1]
    for name in names:
        try:
            return gpu.shader.from_builtin(name), name
        except (ValueError, TypeError, SystemError):
            continue
    return None, None


def _make_batches(out: Outlines) -> dict:
    from gpu_extras.batch import batch_for_shader

    shader, name = builtin_shader("polyline")
    polyline = shader is not None
    if not polyline:
        shader, name = builtin_shader("smooth")
    b = {"version": out.version, "shader": shader, "polyline": polyline, "name": name}
    b["lines"] = (batch_for_shader(shader, "LINES", {"pos": out.lines, "color": out.colors})
                  if len(out.lines) else None)
    b["weak"] = (batch_for_shader(shader, "LINES", {"pos": out.weak_lines,
                                                   "color": out.weak_colors})
                 if len(out.weak_lines) else None)
    b["doubt"] = _flat_batch(shader, out.doubt_lines, DOUBT_RGBA)
    b["notch"] = _flat_batch(shader, out.notch_lines, NOTCH_RGBA)
    b["cut"] = (batch_for_shader(shader, "LINES", {"pos": out.cut_lines, "color": out.cut_colors})
                if len(out.cut_lines) else None)
    b["infill"] = (batch_for_shader(shader, "LINES", {"pos": out.infill_lines,
                                                     "color": out.infill_colors})
                   if len(out.infill_lines) else None)
    b["weak_infill"] = _flat_batch(shader, out.weak_infill_lines, WEAK_RGBA)
    return b


def _flat_batch(shader, lines: np.ndarray, rgba):
    from gpu_extras.batch import batch_for_shader

    if not len(lines):
        return None
    colors = np.broadcast_to(np.float32(rgba), (len(lines), 4)).copy()
    return batch_for_shader(shader, "LINES", {"pos": lines, "color": colors})


def _draw_batch(b: dict, batch, width: float, region) -> None:
    import gpu

    shader = b["shader"]
    shader.bind()
    if b["polyline"]:
        shader.uniform_float("viewportSize", (region.width, region.height))
        shader.uniform_float("lineWidth", width)
    else:
        gpu.state.line_width_set(width)
    batch.draw(shader)


def _draw():
    """SpaceView3D POST_VIEW callback: draws prepared batches only."""
    ctx = bpy.context
    scene = ctx.scene
    settings = getattr(scene, "osteon_live", None)
    if settings is None:
        return
    st = state.get(scene.name)
    hl = st.highlight if st is not None else None
    shown = (st.shown or st.last) if st is not None else None
    if hl is not None and (not shown or shown.get("analysis") is not hl.get("analysis")):
        hl = None                       # a newer result (or Reset): the highlight is stale
    out = None
    if settings.show_sections:
        _maybe_schedule_refresh(scene.name)
        out = get_outlines(scene.name)
    if out is None and hl is None:
        return
    global _batches
    if out is not None and _batches.get("version") != out.version:
        _batches = _make_batches(out)
    import gpu

    region = ctx.region
    gpu.state.blend_set("ALPHA")
    gpu.state.depth_test_set("NONE")   # outlines lie on the surface: show them all, X-ray like
    if out is not None:
        if settings.show_all_sections and _batches.get("cut") is not None:
            _draw_batch(_batches, _batches["cut"], CUT_WIDTH, region)
        if settings.show_all_sections and _batches.get("lines") is not None:
            _draw_batch(_batches, _batches["lines"], WIDTH, region)
        if settings.show_all_sections and _batches.get("infill") is not None:
            _draw_batch(_batches, _batches["infill"], INFILL_WIDTH, region)
        if _batches.get("weak_infill") is not None:
            _draw_batch(_batches, _batches["weak_infill"], INFILL_WIDTH, region)
        if _batches.get("notch") is not None:
            _draw_batch(_batches, _batches["notch"], NOTCH_WIDTH, region)
        if _batches.get("doubt") is not None:
            _draw_batch(_batches, _batches["doubt"], DOUBT_WIDTH, region)
        if _batches.get("weak") is not None:
            _draw_batch(_batches, _batches["weak"], WEAK_WIDTH, region)
    if hl is not None:
        _draw_highlight(hl, region)
    if _batches.get("polyline") is False:
        gpu.state.line_width_set(1.0)
    gpu.state.blend_set("NONE")


def _draw_highlight(hl: dict, region) -> None:
    if hl.get("batch_version") != hl["version"]:
        shader, name = builtin_shader("polyline")
        polyline = shader is not None
        if not polyline:
            shader, name = builtin_shader("smooth")
        hl["batch"] = {"shader": shader, "polyline": polyline, "name": name,
                       "lines": _flat_batch(shader, hl["lines"], HIGHLIGHT_RGBA)}
        hl["batch_version"] = hl["version"]
    b = hl["batch"]
    if b["lines"] is not None:
        _draw_batch(b, b["lines"], HIGHLIGHT_WIDTH, region)
        if not b["polyline"]:
            import gpu

            gpu.state.line_width_set(1.0)


def _maybe_schedule_refresh(scene_name: str) -> None:
    """A new Analyze/Correct result: compute its outlines in a one-shot timer, not here."""
    st = state.get(scene_name)
    entry = st.last if st is not None else None
    if not entry or st.outlined_last is entry["analysis"]:
        return
    if scene_name in _pending_refresh:
        return
    _pending_refresh.add(scene_name)
    bpy.app.timers.register(lambda: refresh_from_last(scene_name), first_interval=0.0)


def enable() -> bool:
    """Add the draw handler (once).  Never in background mode: returns False there."""
    global _handle
    if bpy.app.background:
        return False
    if _handle is None:
        _handle = bpy.types.SpaceView3D.draw_handler_add(_draw, (), "WINDOW", "POST_VIEW")
    bridge_redraw()
    return True


def disable() -> None:
    global _handle
    if _handle is not None:
        bpy.types.SpaceView3D.draw_handler_remove(_handle, "WINDOW")
        _handle = None
        bridge_redraw()


def is_enabled() -> bool:
    return _handle is not None


def sync(scene) -> bool:
    """Handler present iff the scene's "Show sections" is on or a bone is highlighted (and not
    headless)."""
    settings = getattr(scene, "osteon_live", None) if scene is not None else None
    st = state.get(scene.name) if scene is not None else None
    if settings is not None and (settings.show_sections
                                 or (st is not None and st.highlight is not None)):
        return enable()
    disable()
    return False


classes = ()


def register() -> None:
    pass


def unregister() -> None:
    disable()
    clear()
