"""The bpy-free core: materials, units, colour ramp, report (inside Blender's Python too)."""

import json
from types import SimpleNamespace

import numpy as np
import pytest
from osteon_blender import core


def test_allowable_stress_is_strength_over_safety():
    assert core.allowable_stress(60.0, 2.0) == 30.0
    assert core.MATERIAL_BY_KEY["PLA"].strength_mpa == 60.0
    assert core.MATERIAL_BY_KEY["ABS"].strength_mpa == 40.0
    with pytest.raises(ValueError, match="safety factor"):
        core.allowable_stress(60.0, 0.0)
    with pytest.raises(ValueError, match="strength"):
        core.allowable_stress(-1.0, 2.0)


def test_mm_per_unit_modes():
    ext = np.array([1.0, 2.0, 4.0])
    assert core.mm_per_unit("HEIGHT", 120.0, ext, 1.0) == pytest.approx(30.0)
    assert core.mm_per_unit("LARGEST", 120.0, np.array([8.0, 2.0, 4.0]), 1.0) == pytest.approx(15.0)
    assert core.mm_per_unit("UNITS", 0.0, ext, 0.001) == pytest.approx(1.0)
    assert core.mm_per_unit("UNITS", 0.0, ext, 1.0) == pytest.approx(1000.0)
    with pytest.raises(ValueError, match="zero height"):
        core.mm_per_unit("HEIGHT", 120.0, np.array([1.0, 1.0, 0.0]), 1.0)


def test_colours_blue_to_red_grey_for_culled():
    s = np.array([0.0, 15.0, 30.0, 90.0, 10.0, 29.7])
    culled = np.array([False, False, False, False, True, False])
    c = core.stress_colors(s, 30.0, culled)
    assert c.shape == (6, 4) and c.dtype == np.float32
    assert c[0, 2] > 0.9 and c[0, 0] < 0.1            # 0 MPa: blue
    assert c[2, 0] > 0.9 and c[2, 1] < 0.1 and c[2, 2] < 0.1  # allowable: red
    assert np.allclose(c[3], c[2])                     # above allowable stays red
    assert np.allclose(c[4], core.GREY)                # culled: grey
    # within the limit is never red (issue 35): 0.99 x allowable is orange
    assert c[5, 0] > 0.9 and 0.3 < c[5, 1] < 0.6 and c[5, 2] < 0.1
    assert np.all(c[:, 3] == 1.0)
    # the ramp moves monotonically from blue to red in the red-minus-blue channel
    t = np.linspace(0, 1, 50)
    rb = core.ramp(t)[:, 0] - core.ramp(t)[:, 2]
    assert np.all(np.diff(rb) >= -1e-6) and rb[0] < -0.9 and rb[-1] > 0.9


def test_nan_stress_is_not_red():
    c = core.stress_colors(np.array([np.nan]), 30.0)
    assert c[0, 2] > 0.9


def _analysis(stress, bones, weak):
    stress = np.asarray(stress, float)
    return SimpleNamespace(section_bone=np.asarray(bones), stress=stress,
                           weak=np.asarray(weak), culled=np.zeros(len(stress), bool),
                           max_stress=float(np.nanmax(stress)), safe_modulus=1.0)


def test_report_has_spec_keys_and_is_json():
    a = _analysis([10.0, 45.0, 20.0, np.nan], [0, 1, 1, 2], [False, True, False, False])
    rep = core.build_report(object_name="m", armature_name="a", bone_names=["b0", "b1", "b2"],
                            analysis=a, allowable_mpa=30.0, settings={}, mm_per_unit=2.0)
    for key in ("max_stress_mpa", "allowable_stress_mpa", "weak_bones", "sections", "converged"):
        assert key in rep
    assert rep["weak_bones"] == [{"bone": "b1", "max_stress_mpa": 45.0, "ratio": 1.5,
                                  "stress_mpa": 45.0, "allowable_mpa": 30.0,
                                  "limit": "along layers", "scale": 1.0, "weak": True,
                                  "stress_concentration": None}]  # no corner data given
    assert rep["worst"] == {"bone": "b1", "stress_mpa": 45.0, "allowable_mpa": 30.0,
                            "ratio": 1.5, "limit": "along layers"}
    assert rep["sections"] == 4 and rep["converged"] is False
    assert [b["bone"] for b in rep["bones"]] == ["b1", "b0", "b2"]
    json.loads(json.dumps(rep, allow_nan=False))


def test_report_after_correction():
    before = _analysis([45.0, 10.0], [0, 1], [True, False])
    after = _analysis([29.0, 10.0], [0, 1], [False, False])
    fix = SimpleNamespace(bone_scale=np.array([1.2, 1.0]), rounds=[(0, 1.2, 29.0)],
                          converged=True, reason="no weak section", after=after)
    rep = core.build_report(object_name="m", armature_name="a", bone_names=["x", "y"],
                            analysis=before, corrected_analysis=after, allowable_mpa=30.0,
                            settings={}, mm_per_unit=1.0, correction=fix)
    assert rep["converged"] is True
    assert rep["weak_bones"] == [{"bone": "x", "max_stress_mpa": 29.0, "ratio": 29.0 / 30.0,
                                  "stress_mpa": 29.0, "allowable_mpa": 30.0,
                                  "limit": "along layers", "scale": 1.2, "weak": False,
                                  "stress_concentration": None, "max_stress_before_mpa": 45.0}]
    assert rep["correction"]["rounds"] == 1
    assert rep["correction"]["bone_scale"] == {"x": 1.2}
    assert rep["max_stress_mpa"] == 29.0 and rep["correction"]["max_stress_before_mpa"] == 45.0
