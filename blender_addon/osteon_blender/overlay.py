"""Viewport overlay: the section outlines of the last analysis, coloured by stress ratio.

The outlines are computed OUTSIDE the draw callback, right after an analysis (by the live
mode, or once after the Analyze button when the overlay is on), as world-space line
segments in NumPy arrays; the draw callback only uploads them once per new result and
draws them with the ``gpu`` module (no ``bgl``).  Weak sections (stress > allowable) are
drawn thick and magenta-red, culled (surely safe) ones dark grey, the others blue -> red
by stress / allowable like the ``osteon_stress`` colour layer (darkened so that the lines
stand out on the coloured surface).  Lines are drawn without depth test (X-ray like).

Nothing is drawn, and no draw handler is ever added, in background mode.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import bpy
import numpy as np

from . import core, state

WIDTH = 2.0        # px, ordinary sections
WEAK_WIDTH = 5.0   # px, weak sections
WEAK_RGBA = (1.0, 0.0, 0.75, 1.0)      # magenta-red: stands out on the red (weak) surface
CULLED_RGBA = (0.25, 0.25, 0.25, 0.9)
SHADE = 0.55   # ordinary outlines: the stress colour darkened, to stand out on the surface

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
    version: int = field(default_factory=lambda: next(_versions))

    @property
    def num_sections(self) -> int:
        return len(self.section_ids)


# --------------------------------------------------------------------------- geometry (no bpy)


def _bone_domains(vertex_bone: np.ndarray, faces: np.ndarray, parents: np.ndarray) -> list:
    """Per bone, (faces, vertices) touching a vertex of the bone, its parent, children or
    siblings (where its sections can reach): rows of ``faces`` and their vertex ids."""
    nb = len(parents)
    fb = vertex_bone[faces]                                   # (F, 3)
    near = [{b} for b in range(nb)]
    children: dict[int, list[int]] = {}
    for b, p in enumerate(parents):
        if p >= 0:
            near[b].add(int(p))
            near[int(p)].add(b)
            children.setdefault(int(p), []).append(b)
    for sibs in children.values():
        for b in sibs:
            near[b].update(sibs)
    member = np.zeros((nb, nb), dtype=bool)                   # member[b, c]: c is near b
    for b, cs in enumerate(near):
        member[b, list(cs)] = True
    out = []
    for b in range(nb):
        m = member[b]
        hit = np.flatnonzero(m[fb[:, 0]] | m[fb[:, 1]] | m[fb[:, 2]])
        out.append((faces[hit], np.unique(faces[hit])))
    return out


class DomainCache:
    """Per-bone face domains, kept while the dominant-bone map and topology stay the same."""

    def __init__(self):
        self._key = None
        self._vb = None
        self.domains: list = []

    def get(self, vertex_bone, faces, parents) -> list:
        key = (faces.shape, id(faces), tuple(int(p) for p in parents))
        if key != self._key or self._vb is None or not np.array_equal(self._vb, vertex_bone):
            self.domains = _bone_domains(np.asarray(vertex_bone), faces, np.asarray(parents))
            self._vb = np.array(vertex_bone, copy=True)
            self._key = key
        return self.domains


def _loop_segments(loop: np.ndarray) -> np.ndarray:
    """(N, 3) closed loop -> (2N, 3) LINES endpoints."""
    seg = np.empty((2 * len(loop), 3), dtype=np.float64)
    seg[0::2] = loop
    seg[1::2] = np.roll(loop, -1, axis=0)
    return seg


def compute_outlines(analysis, vertices_mm: np.ndarray, faces: np.ndarray,
                     parents: np.ndarray, mm_per_unit: float,
                     domains: DomainCache | None = None,
                     gap_tolerance: float | None = None) -> Outlines:
    """Outline of every computed section of ``analysis`` (an ``osteon.Analysis`` of
    ``vertices_mm``/``faces``), in world space (Blender units = mm / ``mm_per_unit``).

    Each section is re-cut with ``osteon.slice_section`` at the engine's own plane
    (``section_point``, ``section_normal``) and gap tolerance (1 % of the bounding-box
    diagonal), but only through the faces of its bone's neighbourhood that cross a slab
    around the plane, so the whole pass costs a few ms instead of one whole-mesh cut per
    section.  Pure NumPy + engine: safe to run in a worker thread."""
    import osteon  # the engine (imported by the caller through core.import_engine)

    v = np.asarray(vertices_mm, dtype=np.float64)
    faces = np.asarray(faces)
    parents = np.asarray(parents)
    stress = np.asarray(analysis.stress, dtype=np.float64)
    ratio = stress / float(analysis.allowable_stress)
    valid = np.isfinite(stress)
    if gap_tolerance is None:
        extent = [float(c.max()) - float(c.min()) for c in v.T]   # per column: fast
        gap_tolerance = 0.01 * float(np.linalg.norm(extent))
    doms = (domains or DomainCache()).get(analysis.vertex_bone, faces, parents)
    sb = np.asarray(analysis.section_bone)
    points = np.asarray(analysis.section_point, dtype=np.float64)
    normals = np.asarray(analysis.section_normal, dtype=np.float64)
    normals = normals / np.maximum(np.linalg.norm(normals, axis=1), 1e-300)[:, None]

    ids, weak_ids, segs, weak_segs, cols, weak_cols = [], [], [], [], [], []
    culled = np.asarray(analysis.culled, dtype=bool)
    weak = np.asarray(analysis.weak, dtype=bool)
    for b in np.unique(sb[valid]):
        secs = np.flatnonzero(valid & (sb == b))
        dfaces, dverts = doms[int(b)]                         # (Fd, 3), (Vd,)
        if len(dfaces) == 0:
            continue
        axis = normals[secs].sum(axis=0)
        axis /= max(np.linalg.norm(axis), 1e-300)
        tf = (v @ axis)[dfaces]                                # axial coordinates
        tmin = np.minimum(np.minimum(tf[:, 0], tf[:, 1]), tf[:, 2])
        tmax = np.maximum(np.maximum(tf[:, 0], tf[:, 1]), tf[:, 2])
        # bucket the faces along the axis (radix sort of int16 keys: linear time)
        t0 = float(tmin.min())
        width = max(float(analysis.interval), 1e-9)
        nbins = int(min((float(tmax.max()) - t0) / width + 1, 30000))
        key = np.minimum(((tmin - t0) / width).astype(np.int64), nbins - 1).astype(np.int16)
        order = np.argsort(key, kind="stable")
        start = np.zeros(nbins + 1, dtype=np.int64)
        np.cumsum(np.bincount(key, minlength=nbins), out=start[1:])
        reach = float((tmax - tmin).max())                     # longest face along the axis
        radius = None   # how far the domain reaches from the axis (for tilted planes)
        for s in secs:
            n = normals[s]
            c = float(n @ axis)
            ts = float(points[s] @ axis)
            if c < 0.26:                                       # plane nearly along the bone
                cand = dfaces
            else:
                if radius is None:
                    rel = v[dverts] - points[secs[0]]
                    r2 = np.einsum("ij,ij->i", rel, rel) - (rel @ axis) ** 2
                    radius = float(np.sqrt(max(float(r2.max()), 0.0)))
                m = radius * np.sqrt(max(0.0, 1.0 - c * c)) / c + 1e-9
                lo = int(np.clip((ts - m - reach - t0) // width, 0, nbins))
                hi = int(np.clip((ts + m - t0) // width + 1, 0, nbins))
                sel = order[start[lo]:start[hi]]
                sel = sel[(tmin[sel] <= ts + m) & (tmax[sel] >= ts - m)]
                cand = dfaces[sel]
            if len(cand) == 0:
                continue
            d = v[cand] @ n - float(points[s] @ n)             # (f, 3) signed distances
            below, above = d <= 0.0, d >= 0.0
            cand = cand[(below[:, 0] | below[:, 1] | below[:, 2])
                        & (above[:, 0] | above[:, 1] | above[:, 2])]
            if len(cand) == 0:
                continue
            used, local = np.unique(cand, return_inverse=True)
            cut = osteon.slice_section(v[used], local.reshape(-1, 3).astype(np.int32),
                                       points[s], n, gap_tolerance)
            if not cut["found"] or len(cut["outer"]) < 2:
                continue
            loops = [cut["outer"], *cut["holes"]]
            seg = np.concatenate([_loop_segments(np.asarray(lp)) for lp in loops if len(lp) >= 2])
            if weak[s]:
                weak_ids.append(s)
                weak_segs.append(seg)
                weak_cols.append(np.broadcast_to(np.float32(WEAK_RGBA), (len(seg), 4)))
            else:
                ids.append(s)
                segs.append(seg)
                rgba = (CULLED_RGBA if culled[s]
                        else (*(SHADE * core.ramp(np.array([ratio[s]]))[0]).tolist(), 1.0))
                cols.append(np.broadcast_to(np.float32(rgba), (len(seg), 4)))

    k = float(mm_per_unit)

    def pack(parts, width):
        if not parts:
            return np.empty((0, width), dtype=np.float32)
        return np.ascontiguousarray(np.concatenate(parts), dtype=np.float32)

    lines = pack(segs, 3) / np.float32(k)
    weak_lines = pack(weak_segs, 3) / np.float32(k)
    all_ids = np.array(sorted(ids + weak_ids), dtype=np.int64)
    return Outlines(lines=lines, colors=pack(cols, 4), weak_lines=weak_lines,
                    weak_colors=pack(weak_cols, 4), section_ids=all_ids,
                    weak_ids=np.array(sorted(weak_ids), dtype=np.int64))


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


def clear() -> None:
    for st in state.all_states():
        st.outlines = st.outlined_last = None
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
        out = compute_outlines(analysis, inp.vertices_mm, inp.faces, inp.skeleton.parents,
                               inp.mm_per_unit)
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
    return b


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
    if settings is None or not settings.show_sections:
        return
    _maybe_schedule_refresh(scene.name)
    out = get_outlines(scene.name)
    if out is None:
        return
    global _batches
    if _batches.get("version") != out.version:
        _batches = _make_batches(out)
    import gpu

    region = ctx.region
    gpu.state.blend_set("ALPHA")
    gpu.state.depth_test_set("NONE")   # outlines lie on the surface: show them all, X-ray like
    if _batches.get("lines") is not None:
        _draw_batch(_batches, _batches["lines"], WIDTH, region)
    if _batches.get("weak") is not None:
        _draw_batch(_batches, _batches["weak"], WEAK_WIDTH, region)
    if not _batches["polyline"]:
        gpu.state.line_width_set(1.0)
    gpu.state.blend_set("NONE")


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
    """Handler present iff the scene's "Show sections" is on (and not headless)."""
    settings = getattr(scene, "osteon_live", None) if scene is not None else None
    if settings is not None and settings.show_sections:
        return enable()
    disable()
    return False


classes = ()


def register() -> None:
    pass


def unregister() -> None:
    disable()
    clear()
