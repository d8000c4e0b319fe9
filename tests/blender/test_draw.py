"""The viewport overlay really draws: built-in shader, batches and ``gpu.state`` (no ``bgl``, no
``GPUShader(vert, frag)``) into an offscreen buffer, read back as pixels.

It needs a GPU context.  The bpy 5.x wheel makes one headless (``gpu.init()``, EGL); Blender
3.4 and the bpy 4.5 wheel have none in background mode, so the test skips there (the shader
names it uses for them are the ones ``overlay.builtin_shader`` tries first on those lines)."""

from types import SimpleNamespace

import bpy
import numpy as np
import pytest
from conftest import activate
from osteon_blender import overlay


def _gpu_ready() -> bool:
    import gpu

    if not bpy.app.background:
        return True
    init = getattr(gpu, "init", None)
    if init is None:
        return False
    try:
        init()
    except SystemError:
        return False
    return True


def test_overlay_draws_outlines_offscreen(sample):
    if not _gpu_ready():
        pytest.skip("no GPU context in background mode (Blender < 5.0 has no gpu.init)")
    import gpu
    from mathutils import Matrix

    obj, _arm = sample
    activate(obj)
    bpy.context.scene.osteon.force_n = 60.0  # some sections weak
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    name = bpy.context.scene.name
    overlay.refresh_from_last(name)
    out = overlay.get_outlines(name)
    assert out is not None and len(out.lines) > 0 and len(out.weak_lines) > 0
    b = overlay._make_batches(out)
    assert b["shader"] is not None, "no built-in line shader"
    # top view: x, y of the outlines' bounding box onto the whole square, z flattened
    pts = np.concatenate([out.lines, out.weak_lines]).astype(np.float64)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    span = 1.1 * (hi - lo)[:2].max()
    c = 0.5 * (lo + hi)
    proj = Matrix(((2 / span, 0, 0, -2 * c[0] / span), (0, 2 / span, 0, -2 * c[1] / span),
                   (0, 0, 0, 0), (0, 0, 0, 1)))
    size = 128
    off = gpu.types.GPUOffScreen(size, size)
    try:
        with off.bind():
            fb = gpu.state.active_framebuffer_get()
            fb.clear(color=(0.0, 0.0, 0.0, 0.0))
            gpu.state.depth_test_set("NONE")
            gpu.state.blend_set("ALPHA")
            with gpu.matrix.push_pop(), gpu.matrix.push_pop_projection():
                gpu.matrix.load_matrix(Matrix.Identity(4))
                gpu.matrix.load_projection_matrix(proj)
                region = SimpleNamespace(width=size, height=size)
                overlay._draw_batch(b, b["lines"], overlay.WIDTH, region)
                overlay._draw_batch(b, b["weak"], overlay.WEAK_WIDTH, region)
            gpu.state.blend_set("NONE")
            buf = fb.read_color(0, 0, size, size, 4, 0, "FLOAT")
    finally:
        off.free()
    px = np.array(buf.to_list(), dtype=np.float64).reshape(size, size, 4)
    drawn = px[..., 3] > 0.1
    assert drawn.sum() > 100, "nothing drawn"
    r, g, bl = px[..., 0], px[..., 1], px[..., 2]
    wr, wg, wb = overlay.WEAK_RGBA[:3]
    weak = drawn & (np.abs(r - wr) < 0.1) & (np.abs(g - wg) < 0.1) & (np.abs(bl - wb) < 0.1)
    assert weak.sum() > 10, "no weak-section colour drawn"


def _closed_cylinder(a, b, r, n=48, stations=12):
    """Closed cylinder from a to b (mm): side quads and fan caps, outward faces."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    z = (b - a) / np.linalg.norm(b - a)
    x = np.cross([0.0, 0.0, 1.0] if abs(z[2]) < 0.9 else [1.0, 0.0, 0.0], z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    ring = r * (np.outer(np.cos(t), x) + np.outer(np.sin(t), y))
    v = np.concatenate([a + s * (b - a) + ring for s in np.linspace(0, 1, stations)] + [[a, b]])
    f = []
    for s in range(stations - 1):
        for i in range(n):
            j = (i + 1) % n
            p, q = s * n + i, s * n + j
            f += [[p, q, q + n], [p, q + n, p + n]]
    ca, cb = len(v) - 2, len(v) - 1
    last = (stations - 1) * n
    for i in range(n):
        j = (i + 1) % n
        f += [[ca, j, i], [cb, last + i, last + j]]
    return v, np.array(f, np.int32)


def test_overlay_dashes_the_whole_cut_of_junction_sections():
    # A bar r = 3 with a stub fused at mid-length (two overlapping shells): the bar's sections
    # through the stub are junctions; the overlay draws their core as usual and the whole cut
    # (reaching the stub's top, z = 9) dashed and dimmer.
    import osteon

    bar = _closed_cylinder([0, 0, 0], [40, 0, 0], 3.0, stations=41)
    stub = _closed_cylinder([20, 0, 0], [20, 0, 9], 3.0, stations=10)
    v = np.concatenate([bar[0], stub[0]])
    f = np.concatenate([bar[1], stub[1] + len(bar[0])])
    sk = osteon.Skeleton([[0, 0, 0]], [[40, 0, 0]], [-1])
    a = osteon.analyze(v, f, sk, interval=2.0, keep_outlines=True)
    assert a.junction.sum() == 3
    out = overlay.compute_outlines(a, mm_per_unit=1.0)
    cut_points = sum(len(loop) for s in np.flatnonzero(a.junction)
                     for loop in a.section_cut_loops[s])
    assert 0.45 * cut_points <= len(out.cut_lines) // 2 <= 0.55 * cut_points + 3  # every other
    assert np.allclose(out.cut_colors[:, 3], overlay.CUT_ALPHA)
    assert out.cut_lines[:, 2].max() > 8.9  # the stub's top
    assert np.concatenate([out.lines, out.weak_lines])[:, 2].max() < 3.3  # cores stay at the bar
