"""The "Print settings" sub-panel (issue 31): the wheel's presets as an enum (their sources as
tooltips), the overrides, the one mapping through ``osteon.settings.Settings``; the overlay's
sparse-infill loops inside a printed section's outline. Scene: a round bar (one bone)."""

import bpy
import numpy as np
import pytest
from conftest import empty_scene, one_bone_rig
from osteon import profiles
from osteon.settings import engine_takes_print_profile
from osteon_blender import core, overlay, state
from test_draw import _closed_cylinder

needs_printed_engine = pytest.mark.skipif(
    not engine_takes_print_profile(),
    reason="this engine has no print_profile= yet (print-core's branch, issue 31)")


@pytest.fixture
def bar(addon):
    """A round bar r = 6 mm, 60 mm along x, one bone, printed at its own size (1 unit = 1 mm)."""
    empty_scene()
    v, f = _closed_cylinder([0, 0, 0], [60, 0, 0], 6.0, stations=31)
    obj, arm = one_bone_rig("bar", v.tolist(), f.tolist(), "b", (0, 0, 0), (60, 0, 0))
    s = bpy.context.scene.osteon
    s.size_mode, s.print_size_mm, s.interval_mm, s.force_n = "LARGEST", 60.0, 4.0, 20.0
    return obj, arm


def test_print_settings_map_through_the_wheels_settings(addon):
    empty_scene()
    s = bpy.context.scene.osteon
    ps = s.print_settings
    prop = ps.bl_rna.properties["profile"]
    presets = profiles.print_profiles()
    assert [e.identifier for e in prop.enum_items] == list(presets)
    for key, p in presets.items():  # the tooltip is the preset's source
        assert prop.enum_items[key].description == p.source
    assert ps.profile == "solid" and core.settings_of(s).profile() == profiles.PrintProfile.solid()
    ps.profile = "cura"
    assert core.settings_of(s).profile() == presets["cura"]  # no overrides unless asked
    ps.customize = True
    assert (ps.perimeters, ps.pattern) == (presets["cura"].perimeters, presets["cura"].pattern)
    assert ps.infill_percent == pytest.approx(100 * presets["cura"].infill)
    ps.perimeters, ps.infill_percent, ps.pattern = 3, 40.0, "gyroid"
    p = core.settings_of(s).profile()
    assert (p.perimeters, p.pattern) == (3, "gyroid") and p.infill == pytest.approx(0.4)
    assert p.line_width == pytest.approx(presets["cura"].line_width)
    ps.profile = "resin_hollow"  # a new preset: its own numbers, the shell only
    ps.shell_mm = 3.0
    p = core.settings_of(s).profile()
    assert p.kind == "resin_hollow" and p.shell == pytest.approx(3.0)


def test_overlay_draws_the_infill_loops_inside_the_outline(engine):
    import osteon

    v, f = _closed_cylinder([0, 0, 0], [40, 0, 0], 6.0, stations=21)
    sk = osteon.Skeleton([[0, 0, 0]], [[40, 0, 0]], [-1])
    printed = {"print_profile": "prusaslicer"} if engine_takes_print_profile() else {}
    a = osteon.analyze(v, f, sk, interval=4.0, keep_outlines=True, **printed)
    assert (getattr(a, "infill_outline_section_start", None) is not None) == bool(printed)
    if not printed:
        # an engine without printed sections: the loops packed as the printed engine packs
        # them (like outline_*), here each outline shrunk to half around its centre
        pts = np.asarray(a.outline_points, float).copy()
        ls, ss = np.asarray(a.outline_loop_start), np.asarray(a.outline_section_start)
        sec = np.repeat(np.repeat(np.arange(len(ss) - 1), np.diff(ss)), np.diff(ls))
        pts = a.section_center[sec] + 0.5 * (pts - a.section_center[sec])
        a.infill_outline_points, a.infill_outline_loop_start = pts, ls
        a.infill_outline_section_start = ss
    out = overlay.compute_outlines(a, mm_per_unit=1.0)
    infill = np.concatenate([out.infill_lines, out.weak_infill_lines])
    assert len(infill) > 0 and np.allclose(out.infill_colors[:, 3], overlay.INFILL_ALPHA)
    r_outline = np.hypot(*np.concatenate([out.lines, out.weak_lines])[:, 1:].T).max()
    assert r_outline == pytest.approx(6.0, abs=1e-4)
    # inside the walls and skins: the bar lies (build +Z), so 2 perimeters (0.84 mm deep,
    # print-core's rule) at its sides (y) and 4 × 0.2 mm skins above and below (z); the
    # stand-in loops lie at half the radius
    y, z = np.abs(infill[:, 1]), np.abs(infill[:, 2])
    assert y[z < 0.5].max() < 6.0 - 0.8 and z[y < 0.5].max() < 6.0 - 0.75
    assert np.hypot(y, z).max() < 6.0 - 0.5


@needs_printed_engine
def test_analyze_with_a_print_profile(bar):
    s = bpy.context.scene.osteon
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    solid = state.get(bpy.context.scene).last["report"]
    s.print_settings.profile = "prusaslicer"
    s.print_settings.customize = True
    s.print_settings.infill_percent = 0.0
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    printed = state.get(bpy.context.scene).last["report"]
    assert solid["print_profile"]["kind"] == "solid"
    assert printed["print_profile"]["kind"] == "fdm" and printed["print_profile"]["infill"] == 0
    assert printed["settings"]["print_profile"] == "prusaslicer"
    # walls and skins only: the printed W below the solid W, the stress above
    assert printed["max_stress_mpa"] > 1.2 * solid["max_stress_mpa"]


@needs_printed_engine
def test_find_orientation_analyses_the_candidates_as_printed(bar):
    s = bpy.context.scene.osteon
    s.print_settings.profile = "prusaslicer"
    assert bpy.ops.osteon.find_orientation() == {"FINISHED"}
    res = state.get(bpy.context.scene).orientation["result"]
    # each candidate carries its own printed analysis's ratio next to the search's; the last
    # analysis was made with the profile at +Z, so at +Z (the current direction, analysed
    # again) the two agree, and the best is at most that
    assert all("search_ratio" in c for c in res.candidates)
    at_z = [c for c in res.candidates if abs(c["direction"][2]) > 1 - 1e-9]
    assert at_z and at_z[0]["worst_ratio"] == pytest.approx(at_z[0]["search_ratio"], rel=1e-9)
    assert res.worst_ratio <= at_z[0]["worst_ratio"] * (1 + 1e-9)
