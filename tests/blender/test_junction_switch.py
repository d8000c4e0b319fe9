"""The "Junction cores" setting (issue 16, docs/junctions.md) reaches the engine from Blender:
Analyze, live mode and the batch command. The scene: a round bar (r = 3 mm, 40 mm along x, one
bone) with a stub of the same radius fused at mid-length; the bar's three sections through the
stub are junctions (their core is the bar) when the setting is on, whole cuts when it is off."""

import json

import bpy
import numpy as np
import pytest
from conftest import empty_scene, one_bone_rig
from osteon_blender import batch, live, state
from test_draw import _closed_cylinder

R = 3.0
W_ROUND = np.pi * R**3 / 4  # mm³, the bar's own section modulus


@pytest.fixture
def tbar(addon):
    """The T-bar rigged to one bone along the bar (all weights 1), printed at its own size
    (largest dimension 40 mm = 40 Blender units)."""
    empty_scene()
    bar = _closed_cylinder([0, 0, 0], [40, 0, 0], R, stations=41)
    stub = _closed_cylinder([20, 0, 0], [20, 0, 9], R, stations=10)
    v = np.concatenate([bar[0], stub[0]])
    f = np.concatenate([bar[1], stub[1] + len(bar[0])])
    obj, arm = one_bone_rig("tbar", v.tolist(), f.tolist(), "bar", (0, 0, 0), (40, 0, 0))
    s = bpy.context.scene.osteon
    s.size_mode, s.print_size_mm, s.interval_mm = "LARGEST", 40.0, 2.0
    yield obj, arm
    live.stop()


def _through(a):
    """The bar's interior sections whose planes cut the stub (x = 18, 20, 22 mm)."""
    return (a.section_kind == 0) & (np.abs(a.section_param - 20) < R)


def test_junction_cores_setting_reaches_the_engine(tbar):
    s = bpy.context.scene.osteon
    assert s.junction_cores is True  # the default: the cores counted
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    last = state.get(bpy.context.scene).last
    on, rep_on = last["analysis"], last["report"]
    through = _through(on)
    assert through.sum() == 3 and on.junction[through].all() and on.junction.sum() == 3
    np.testing.assert_allclose(on.section_modulus[through], W_ROUND, rtol=0.10)
    assert rep_on["settings"]["junctions"] is True
    assert rep_on["junction_sections"] == [int(i) for i in np.flatnonzero(through)]
    s.junction_cores = False
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    last = state.get(bpy.context.scene).last
    off, rep_off = last["analysis"], last["report"]
    assert rep_off["settings"]["junctions"] is False
    assert not off.junction.any() and rep_off["junction_sections"] == []
    assert not any("junction" in r["flags"] for r in rep_off["section_table"])
    # the stub's sections: the whole cut (the stub counted), as the core run measured it
    np.testing.assert_allclose(off.section_modulus[through], on.section_cut_modulus[through],
                               rtol=1e-9)
    assert (off.section_modulus[through] > 1.6 * W_ROUND).all()


def test_batch_command_takes_no_junction_cores(tbar, tmp_path):
    obj, _arm = tbar
    for name, extra in (("on", []), ("off", ["--no-junction-cores"])):
        path = tmp_path / f"{name}.json"
        assert batch.run(["--report", str(path), "--object", obj.name, *extra]) == 0
        rep = json.loads(path.read_text())
        assert rep["settings"]["junctions"] is (name == "on")
        assert len(rep["junction_sections"]) == (3 if name == "on" else 0)


def test_live_rebuilds_its_analyzer_when_junction_cores_change(tbar):
    s = bpy.context.scene.osteon
    live.start(bpy.context)
    sess = live.session()
    first = sess.analyzer
    assert sess.last_result.analysis.junction.sum() == 3
    s.junction_cores = False
    bpy.context.view_layer.update()  # the depsgraph handler notes the change
    assert sess.dirty
    live.update_now()
    a = sess.last_result.analysis
    assert sess.analyzer is not first and not a.junction.any()
    assert (a.section_modulus[_through(a)] > 1.6 * W_ROUND).all()
    s.junction_cores = True
    bpy.context.view_layer.update()
    live.update_now()
    assert sess.last_result.analysis.junction.sum() == 3


def test_live_follows_the_print_direction(tbar):
    """Every engine setting reaches the live Analyzer, not only the ones once listed: with layers
    at half strength, turning the bar (along x) from lying in the layers (print +Z) to standing
    across them (print +X) halves the allowable stress of its sections (Tsai-Hill at θ = 0,
    docs/printing.md), as a fresh analysis with that direction gives."""
    s = bpy.context.scene.osteon
    s.layer_strength_ratio = 0.5
    live.start(bpy.context)
    sess = live.session()
    bar = sess.last_result.analysis.section_bone == 0
    before = sess.last_result.analysis.section_allowable[bar]
    s.print_direction = "AXIS"
    s.print_axis = "+X"
    bpy.context.view_layer.update()  # the depsgraph handler notes the change
    assert sess.dirty
    live.update_now()
    a = sess.last_result.analysis
    after = a.section_allowable[a.section_bone == 0]
    np.testing.assert_allclose(after, 0.5 * before, rtol=1e-9)
