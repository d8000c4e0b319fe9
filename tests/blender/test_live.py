"""Live mode and the section overlay (issue 7), inside real Blender (3.4.1 binary and the
bpy 4.5 wheel; both run headless, so the overlay must stay off)."""

from __future__ import annotations

import bpy
import numpy as np
import pytest
from conftest import activate, empty_scene
from osteon_blender import bridge, core, live, overlay


def _group_weights(obj, name: str) -> np.ndarray:
    w = np.zeros(len(obj.data.vertices))
    g = obj.vertex_groups[name].index
    for v in obj.data.vertices:
        for e in v.groups:
            if e.group == g:
                w[v.index] = e.weight
    return w


def _ramp_position(rgba: np.ndarray) -> np.ndarray:
    """Invert the colour ramp: position t in [0, 1] (0 = blue = 0 MPa, 1 = red = allowable)
    of each colour, by the nearest of 1001 ramp samples."""
    t = np.linspace(0.0, 1.0, 1001)
    table = core.ramp(t)
    d = ((rgba[:, None, :3] - table[None, :, :]) ** 2).sum(axis=2)
    return t[np.argmin(d, axis=1)]


@pytest.fixture
def live_sample(sample):
    obj, arm = sample
    activate(obj)
    yield obj, arm
    live.stop()
    if hasattr(bpy.context.scene, "osteon_live"):
        bpy.context.scene.osteon_live.show_sections = False


def test_registered_with_the_addon(addon):
    assert hasattr(bpy.types.Scene, "osteon_live")
    assert hasattr(bpy.types, "OSTEON_PT_live")
    assert bpy.types.OSTEON_PT_live.bl_parent_id == "OSTEON_PT_main"
    assert live._on_load_post in bpy.app.handlers.load_post
    s = bpy.context.scene.osteon_live
    assert s.throttle_ms == 50 and not s.enabled and not s.show_sections


def test_thinner_limb_gets_higher_stress_live(live_sample):
    obj, arm = live_sample
    r = live.start(bpy.context)
    assert r.updates == 1 and r.status == "live"
    assert live.handlers_installed()
    assert live._on_depsgraph in bpy.app.handlers.depsgraph_update_post
    assert bpy.app.timers.is_registered(live._tick)
    before_layer = bridge.read_point_colors(obj.data)
    assert before_layer is not None and len(before_layer) == len(obj.data.vertices)
    before = live.session().last_result.analysis
    limb = _group_weights(obj, "forearm.L") > 0.9
    other = _group_weights(obj, "forearm.R") > 0.9
    assert limb.sum() > 50 and other.sum() > 50

    live.session().dirty = False
    arm.pose.bones["forearm.L"].scale = (0.7, 1.0, 0.7)      # thinner across the bone
    bpy.context.view_layer.update()
    assert live.session().dirty, "the depsgraph handler did not note the pose change"
    r = live.update_now()
    assert r.updates == 2
    after = live.session().last_result.analysis
    layer = bridge.read_point_colors(obj.data)
    # the layer holds the new analysis ...
    res = live.session().last_result
    k = res.mm_per_unit
    np.testing.assert_allclose(   # Analyze's colours of this analysis (core.result_colors)
        layer, core.result_colors(after, res.inputs.skeleton.heads * k,
                                  res.inputs.skeleton.tails * k), atol=1e-6)
    # ... stress on the thinner forearm went up by about 1 / 0.7^3 (section modulus ~ s^3)
    ratio = after.vertex_stress[limb].mean() / before.vertex_stress[limb].mean()
    assert 2.0 < ratio < 3.5, ratio
    # ... the colours moved towards red there, and the other forearm barely changed
    t0, t1 = _ramp_position(before_layer[limb]), _ramp_position(layer[limb])
    assert t1.mean() > t0.mean() + 0.1
    assert np.count_nonzero(t1 > t0 + 1e-3) > 0.5 * limb.sum()
    other_ratio = after.vertex_stress[other].mean() / before.vertex_stress[other].mean()
    assert abs(other_ratio - 1.0) < 0.1, other_ratio
    # nothing moved since: no new analysis
    assert live.update_now().updates == 2
    # readout
    assert r.max_stress_mpa == pytest.approx(float(after.max_stress))
    assert r.allowable_mpa == pytest.approx(30.0)
    # the weakest bone is the governing section's: highest stress / ITS allowable (layers)
    worst = int(np.nanargmax(np.where(np.isfinite(after.stress), after.stress_ratio, -np.inf)))
    assert r.weakest_bone == after.bone_names[int(after.section_bone[worst])]
    assert r.weakest_ratio == pytest.approx(float(after.stress_ratio[worst]), rel=1e-12)


def test_timer_path_runs_in_a_worker_and_respects_the_throttle(live_sample):
    _obj, arm = live_sample
    scene = bpy.context.scene
    scene.osteon_live.throttle_ms = 0
    live.start(bpy.context)
    sess = live.session()
    arm.pose.bones["shin.L"].scale = (0.8, 1.0, 0.8)
    bpy.context.view_layer.update()
    assert sess.dirty
    live._tick()                                    # reads, submits to the worker
    assert sess.future is not None
    sess.future.result(timeout=60)
    live._tick()                                    # publishes
    assert sess.future is None and sess.readout.updates == 2
    # the pose is still and "Show sections" is on: the next tick computes the outlines of
    # that result in the worker, the one after shows them
    scene.osteon_live.show_sections = True
    bpy.context.view_layer.update()                 # our own colour write: noted, no change
    sess.next_allowed = 0.0                         # (skip the wait after an update)
    live._tick()
    assert sess.future is None and sess.outline_future is not None
    sess.outline_future.result(timeout=60)
    live._tick()
    assert sess.outlined is sess.last_result.analysis
    assert overlay.get_outlines(scene.name).num_sections > 0 and sess.readout.updates == 2
    # a long throttle: the next change waits
    scene.osteon_live.throttle_ms = 10000
    sess.next_allowed = __import__("time").perf_counter() + 10.0
    arm.pose.bones["shin.L"].scale = (0.6, 1.0, 0.6)
    bpy.context.view_layer.update()
    wait = live._tick()
    assert sess.future is None and sess.dirty and sess.readout.updates == 2
    assert 0.0 < wait <= 0.25


def test_settings_change_reanalyses(live_sample):
    live.start(bpy.context)
    s = bpy.context.scene.osteon
    first = live.readout(bpy.context.scene).max_stress_mpa
    s.force_n = 40.0                                # twice the force -> twice the stress
    bpy.context.view_layer.update()
    assert live.session().dirty
    r = live.update_now()
    assert r.max_stress_mpa == pytest.approx(2.0 * first, rel=1e-6)


def test_live_off_removes_handlers_and_timer(live_sample):
    scene = bpy.context.scene
    scene.osteon_live.enabled = True
    assert live.is_live(scene) and scene.osteon_live.enabled
    assert live.handlers_installed()
    scene.osteon_live.enabled = False
    assert not live.is_live() and not scene.osteon_live.enabled
    assert live._on_depsgraph not in bpy.app.handlers.depsgraph_update_post
    assert live._on_frame not in bpy.app.handlers.frame_change_post
    assert not bpy.app.timers.is_registered(live._tick)
    assert live.readout(scene).status == "off"
    with pytest.raises(core.OsteonError):
        live.update_now()


def test_file_load_and_unregister_end_live(live_sample, addon):
    scene = bpy.context.scene
    scene.osteon_live.enabled = True
    assert live.handlers_installed()
    empty_scene()                                   # a new file: load_post ends the session
    assert not live.is_live() and not live.handlers_installed()
    obj, _arm = __import__("osteon_blender.sample", fromlist=["build"]).build()
    activate(obj)
    bpy.context.scene.osteon_live.enabled = True
    assert live.handlers_installed()
    addon.unregister()
    try:
        assert not live.is_live() and not live.handlers_installed()
        assert live._on_load_post not in bpy.app.handlers.load_post
        assert not hasattr(bpy.types.Scene, "osteon_live")
    finally:
        addon.register()


def test_live_error_is_reported_not_raised_by_the_toggle(addon):
    empty_scene()
    bpy.context.scene.osteon_live.enabled = True    # nothing to analyse
    assert not live.is_live()
    assert live.readout(bpy.context.scene).status.startswith("error: No active object")
    assert not live.handlers_installed()


def test_overlay_skipped_headless_but_outlines_computed(live_sample, engine):
    obj, _arm = live_sample
    assert bpy.app.background
    scene = bpy.context.scene
    scene.osteon_live.show_sections = True
    assert not overlay.is_enabled() and overlay._handle is None
    assert overlay.enable() is False and overlay._handle is None
    live.start(bpy.context)
    out = overlay.get_outlines(scene.name)
    assert out is not None and out.num_sections > 0 and len(out.lines) > 0
    res = live.session().last_result
    a = res.analysis
    # the same sections the engine cuts on the whole mesh (brute force, small rig)
    gap = 0.01 * float(np.linalg.norm(np.ptp(res.vertices_mm, axis=0)))
    full = [s for s in np.flatnonzero(a.valid)
            if engine.slice_section(res.vertices_mm, live.session().faces, a.section_point[s],
                                    a.section_normal[s], gap)["found"]]
    assert len(full) >= 0.9 * a.valid.sum()
    missing = set(full) - set(out.section_ids.tolist())
    assert len(missing) <= 0.05 * len(full), sorted(missing)
    assert set(out.section_ids.tolist()) <= set(np.flatnonzero(a.valid).tolist())
    # weak ones drawn apart, every weak section outlined
    assert set(out.weak_ids.tolist()) == set(np.flatnonzero(a.weak).tolist()) & set(
        out.section_ids.tolist())
    assert len(out.weak_lines) > 0 and np.allclose(out.weak_colors, overlay.WEAK_RGBA)
    # world space, on the section planes, on the mesh surface's scale
    pts = np.concatenate([out.lines, out.weak_lines]).astype(np.float64)
    world = bridge.evaluated_positions(obj, bpy.context.evaluated_depsgraph_get())
    lo, hi = world.min(axis=0), world.max(axis=0)
    assert np.all(pts >= lo - 1e-3) and np.all(pts <= hi + 1e-3)
    s0 = int(out.section_ids[0])
    n = a.section_normal[s0] / np.linalg.norm(a.section_normal[s0])
    p0 = a.section_point[s0] / res.mm_per_unit
    seg = out.lines if s0 not in out.weak_ids else out.weak_lines
    d = np.abs((seg.astype(np.float64) - p0) @ n)
    assert d.min() < 1e-4                          # at least its own loop lies on its plane
    assert overlay._handle is None                 # still no draw handler


def test_overlay_outlines_of_the_analyze_button(sample, engine):
    obj, _arm = sample
    activate(obj)
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    from osteon_blender import service as common

    overlay.refresh_from_last(bpy.context.scene.name)
    out = overlay.get_outlines(bpy.context.scene.name)
    a = common.LAST[bpy.context.scene.name]["analysis"]
    assert out is not None and 0.9 * a.valid.sum() <= out.num_sections <= a.valid.sum()


def test_live_result_is_the_panels_and_analyzes(live_sample):
    """One verdict (issue 35): while Live runs, the summary and the rows show Live's result
    (never "Not analysed yet" beside Live's numbers), Live's box names the same governing
    section, and Analyze on the same pose gives the same rows, verdict and colours."""
    from osteon_blender.ui import doubt_ui

    obj, _arm = live_sample
    s = bpy.context.scene.osteon
    assert doubt_ui.summary_lines(s)[0][0] == "Not analysed yet"
    live.start(bpy.context)
    lines = [t for t, _ in doubt_ui.summary_lines(s)]
    assert lines[0].endswith("(Live)") and s.result_source == "live"
    r = live.readout(bpy.context.scene)
    assert (r.weakest_bone, r.weakest_ratio) == (s.worst_bone, pytest.approx(s.worst_ratio))
    assert r.worst_stress_mpa / r.worst_allowable_mpa == pytest.approx(r.weakest_ratio, rel=1e-6)
    live_rows = [(x.name, round(x.ratio, 6), round(x.stress_mpa, 4), x.limit) for x in s.weak_bones]
    live_worst = (s.worst_bone, s.worst_ratio, s.worst_stress_mpa, s.worst_allowable_mpa)
    live_layer = bridge.read_point_colors(obj.data).copy()
    live.stop()
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    assert s.result_source == "analyze"
    assert [(x.name, round(x.ratio, 6), round(x.stress_mpa, 4), x.limit)
            for x in s.weak_bones] == live_rows
    assert s.worst_bone == live_worst[0]
    assert (s.worst_ratio, s.worst_stress_mpa, s.worst_allowable_mpa) == pytest.approx(
        live_worst[1:], rel=1e-6)
    np.testing.assert_allclose(bridge.read_point_colors(obj.data), live_layer, atol=1e-6)


def test_the_section_rows_come_once_the_pose_is_still(live_sample):
    """Per update Live's report leaves out the per-section rows (issue 34: the panel does not
    show them); a look that finds nothing moved, or Live switched off, fills them in, the same
    rows as the wheel's report of that analysis, so the report the panel keeps is whole."""
    from osteon import report as wheel_report

    _obj, arm = live_sample
    live.start(bpy.context)
    arm.pose.bones["forearm.L"].scale = (0.8, 1.0, 0.8)
    bpy.context.view_layer.update()
    assert live.update_now().updates == 2
    res = live.session().last_result
    assert res.report["section_table"] is None
    assert res.report["weak_bones"] == core.build_report(
        object_name=res.report["object"], armature_name=res.report["armature"],
        bone_names=res.names, analysis=res.analysis, allowable_mpa=res.report[
            "allowable_stress_mpa"], settings=res.report["settings"],
        mm_per_unit=res.mm_per_unit)["weak_bones"]
    assert live.update_now().updates == 2                    # nothing moved: the pose is still
    rows = res.report["section_table"]
    assert rows == wheel_report.section_rows(res.analysis, res.names)
    assert len(rows) == res.analysis.num_sections > 0
    arm.pose.bones["forearm.L"].scale = (0.75, 1.0, 0.75)
    bpy.context.view_layer.update()
    assert live.update_now().updates == 3
    res = live.session().last_result
    assert res.report["section_table"] is None
    live.stop()
    assert len(res.report["section_table"]) == res.analysis.num_sections
