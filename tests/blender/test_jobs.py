"""Analyze and Correct on any model (issue 20): the section guard, cancel, the execute path."""

import threading
import time

import bpy
import numpy as np
import pytest
from osteon.settings import SECTION_LIMIT
from osteon_blender import bridge, prefs, service
from osteon_blender.ops import OSTEON_OT_analyze, OSTEON_OT_correct
from osteon_blender.ops._base import OsteonJobOperator


def _kilometre(obj, arm):
    """The figurine x1000 in scene units (1 unit = 1 m): 2.45 km tall."""
    s = bpy.context.scene.osteon
    s.size_mode = "UNITS"
    arm.scale = (1000.0, 1000.0, 1000.0)
    bpy.context.view_layer.update()
    return s


def test_guard_refuses_a_kilometre_model_at_once(sample, engine):
    obj, arm = sample
    _kilometre(obj, arm)
    inp = service.gather(bpy.context)
    # the estimate is the engine's exact count for the skeleton it would get, in mm
    n = engine.estimate_sections(service.engine_skeleton(engine, inp), 2.0)
    assert n > 2_000_000
    size_km = float(np.max(inp.vertices_mm.max(0) - inp.vertices_mm.min(0))) / 1e6
    assert 2.3 < size_km < 2.5
    expect = f"{n:,}".replace(",", " ") + f" sections at 2 mm on a {size_km:.3g} km model"
    t0 = time.perf_counter()
    with pytest.raises(RuntimeError, match=expect + ": check the print size"):
        bpy.ops.osteon.analyze()
    assert time.perf_counter() - t0 < 1.0
    # nothing was written: no stress layer, no result, pose untouched
    assert obj.data.attributes.get(bridge.LAYER) is None
    assert not bpy.context.scene.osteon.has_result
    # Correct too (and it leaves the pose as it was)
    with pytest.raises(RuntimeError, match="check the print size"):
        bpy.ops.osteon.correct()
    assert all(tuple(p.scale) == (1.0, 1.0, 1.0) for p in arm.pose.bones)
    # a UI click (invoke) in background mode runs the execute path: the same refusal
    with pytest.raises(RuntimeError, match="check the print size"):
        bpy.ops.osteon.analyze("INVOKE_DEFAULT")
    assert obj.data.attributes.get(bridge.LAYER) is None
    assert prefs.max_sections(bpy.context) == SECTION_LIMIT


def test_execute_runs_within_the_limit_and_the_limit_can_be_lifted(sample, engine):
    s = bpy.context.scene.osteon
    assert bpy.ops.osteon.analyze("INVOKE_DEFAULT") == {"FINISHED"}
    base = s.sections
    assert base == engine.estimate_sections(
        service.engine_skeleton(engine, service.gather(bpy.context)), 2.0)
    # over a limit set on the operator: refused; limit 0: runs
    with pytest.raises(RuntimeError, match=f"{base} sections at 2 mm on a 120 mm model"):
        bpy.ops.osteon.analyze(max_sections=base - 1)
    assert bpy.ops.osteon.analyze(max_sections=base) == {"FINISHED"}
    assert bpy.ops.osteon.analyze(max_sections=0) == {"FINISHED"}
    assert s.sections == base


def _cancel_after(job, work, sections):
    """Run ``work`` in a thread as the modal operator does; cancel after ``sections``."""
    out = {}

    def body():
        try:
            out["value"] = work()
        except BaseException as e:  # noqa: BLE001
            out["error"] = e

    t = threading.Thread(target=body)
    t.start()
    deadline = time.perf_counter() + 120
    while job.progress.sections_done < sections and t.is_alive():
        assert time.perf_counter() < deadline
        time.sleep(0.001)
    job.progress.cancel()
    t.join()
    return out


@pytest.mark.parametrize("which", ["analyze", "correct"])
def test_cancel_leaves_the_scene_unchanged(sample, engine, which):
    # The job steps the modal operator drives: a long run (~10 000 sections) cancelled after
    # 300 sections stops with Cancelled, and the scene is as before (no layer, no result, the
    # pose of an earlier correction kept).
    obj, arm = sample
    s = bpy.context.scene.osteon
    if which == "correct":
        s.force_n = 60.0
        assert bpy.ops.osteon.correct() == {"FINISHED"}
        scales = {p.name: tuple(p.scale) for p in arm.pose.bones}
        assert any(v != (1.0, 1.0, 1.0) for v in scales.values())
        layer_before = bridge.read_point_colors(obj.data).copy()
    s.print_size_mm = 9300.0  # ~10 000 sections at 2 mm
    job = service.Job(bpy.context, progress=engine.Progress(), max_sections=0)
    steps = (service.analyze_steps if which == "analyze" else service.correct_steps)(job)
    work = next(steps)
    out = _cancel_after(job, work, 300)
    assert isinstance(out.get("error"), engine.Cancelled), out
    assert 300 <= job.progress.sections_done < job.progress.sections_total // 2
    job.context = bpy.context
    with pytest.raises(engine.Cancelled):
        steps.throw(out["error"])
    if which == "analyze":
        assert obj.data.attributes.get(bridge.LAYER) is None
        assert not s.has_result
    else:
        for p in arm.pose.bones:
            assert tuple(p.scale) == pytest.approx(scales[p.name], rel=1e-6)
        assert np.array_equal(bridge.read_point_colors(obj.data), layer_before)


def test_job_operators_are_the_ones_the_panel_calls():
    assert issubclass(OSTEON_OT_analyze, OsteonJobOperator)
    assert issubclass(OSTEON_OT_correct, OsteonJobOperator)
