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
