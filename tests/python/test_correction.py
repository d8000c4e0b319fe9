"""Correction (docs/method.md, Correction; paper §5): per-bone cross-section scaling with linear blend skinning."""

import numpy as np
import osteon
import pytest
from rigged_models import load
from scipy import sparse
from shapes import circle, cylinder_along, merge, prism, rectangle, revolve


def bar():
    v, f = prism(circle(5.0, 96), 100.0)
    sk = osteon.Skeleton([[0, 0, 0]], [[100, 0, 0]], [-1], ["bar"])
    return v, f, sk, np.ones((len(v), 1))


def test_bar_at_twice_the_allowable_is_fixed_in_one_round_by_cbrt_2():
    v, f, sk, w = bar()
    before = osteon.analyze(v, f, sk, w, force=10.0)
    allowable = before.max_stress / 2
    fix = osteon.correct(v, f, sk, w, force=10.0, allowable_stress=allowable)
    assert fix.converged and len(fix.rounds) == 1
    assert fix.bone_scale[0] == pytest.approx(2 ** (1 / 3), rel=0.02)
    assert not fix.after.weak.any()
    # length kept: x is along the bone and untouched; radius scaled
    assert np.array_equal(fix.vertices[:, 0], v[:, 0])
    r0 = np.linalg.norm(v[:, 1:], axis=1)
    r1 = np.linalg.norm(fix.vertices[:, 1:], axis=1)
    assert np.allclose(r1, fix.bone_scale[0] * r0)
    assert fix.volume_change_percent == pytest.approx(100 * (fix.bone_scale[0] ** 2 - 1), rel=1e-6)


def limb_on_body():
    # the limb is sunk 3 mm into the body (a detached limb would be a loose piece: no load)
    body = revolve(np.linspace(0, 60, 31), np.full(31, 15.0), 64)
    limb = cylinder_along([57, 0, 0], [140, 0, 0], 2.0)
    v, f = merge(body, limb)
    nb = len(body[0])
    sk = osteon.Skeleton([[0, 0, 0], [60, 0, 0]], [[60, 0, 0], [140, 0, 0]], [-1, 0],
                         ["body", "limb"])
    w = np.zeros((len(v), 2))
    w[:nb, 0] = 1
    w[nb:, 1] = 1
    return v, f, sk, w, nb


def test_thin_limb_is_fixed_and_the_body_does_not_move():
    v, f, sk, w, nb = limb_on_body()
    fix = osteon.correct(v, f, sk, sparse.csr_matrix(w), force=5.0, allowable_stress=30.0)
    assert fix.before.weak.any()
    assert fix.converged and not fix.after.weak.any()
    assert fix.bone_scale[0] == 1.0 and fix.bone_scale[1] > 1.0
    assert np.array_equal(fix.vertices[:nb], v[:nb])  # bitwise: no weight on a scaled bone
    assert np.array_equal(fix.vertices[nb:, 0], v[nb:, 0])  # limb length kept
    assert fix.max_displacement > 0


def test_reanalysing_the_corrected_mesh_gives_after():
    v, f, sk, w, _nb = limb_on_body()
    fix = osteon.correct(v, f, sk, w, force=5.0, allowable_stress=30.0)
    again = osteon.analyze(fix.vertices, f, sk, w, force=5.0, allowable_stress=30.0)
    assert np.array_equal(again.stress, fix.after.stress, equal_nan=True)
    assert np.array_equal(again.weak, fix.after.weak)


def test_skin_matches_the_correction_vertices():
    v, f, sk, w, _nb = limb_on_body()
    fix = osteon.correct(v, f, sk, w, force=5.0, allowable_stress=30.0)
    assert np.allclose(osteon.skin(v, sk, w, fix.bone_scale), fix.vertices, atol=1e-12)


def test_blended_weights_scale_by_the_weighted_mean():
    v, _f, _sk, _w = bar()
    two = osteon.Skeleton([[0, 0, 0], [0, 0, 0]], [[100, 0, 0], [100, 0, 0]], [-1, 0])
    weights = np.column_stack([np.full(len(v), 0.25), np.full(len(v), 0.75)]) * 3  # unnormalised
    out = osteon.skin(v, two, weights, [1.0, 2.0])
    r0 = np.linalg.norm(v[:, 1:], axis=1)
    r1 = np.linalg.norm(out[:, 1:], axis=1)
    assert np.allclose(r1, (0.25 * 1 + 0.75 * 2) * r0)


def test_max_scale_stops_the_loop_with_a_reason():
    v, f, sk, w, _nb = limb_on_body()
    fix = osteon.correct(v, f, sk, w, force=50.0, allowable_stress=30.0, max_scale=1.1,
                         max_rounds=50)
    assert not fix.converged
    assert fix.bone_scale.max() <= 1.1 + 1e-12
    assert "max_scale" in fix.reason and "limb" in fix.reason
    assert len(fix.rounds) <= 50
    assert len(fix.unfixed_sections) == int(fix.after.weak.sum()) > 0


def test_unweighted_part_cannot_be_fixed_and_the_loop_ends():
    v, f, sk, w, nb = limb_on_body()
    w[nb:] = 0.0  # the limb follows no bone: scaling cannot thicken it
    fix = osteon.correct(v, f, sk, w, force=5.0, allowable_stress=30.0, max_rounds=20)
    assert not fix.converged
    assert np.array_equal(fix.vertices[nb:], v[nb:])
    assert "stay weak" in fix.reason
    assert len(fix.rounds) <= 20


def test_max_rounds_zero_changes_nothing():
    v, f, sk, w, _nb = limb_on_body()
    fix = osteon.correct(v, f, sk, w, force=5.0, allowable_stress=30.0, max_rounds=0)
    assert not fix.converged and len(fix.rounds) == 0
    assert np.array_equal(fix.vertices, v)


def plate():
    """A 12 x 3 mm flat bar along x: thin across z."""
    v, f = prism(rectangle(12.0, 3.0), 100.0)
    sk = osteon.Skeleton([[0, 0, 0]], [[100, 0, 0]], [-1], ["plate"])
    return v, f, sk, np.ones((len(v), 1))


def rectangle_modulus(b, t):
    """Minimum section modulus of a b x t rectangle over all bending directions."""
    return b**2 * t**2 / (6 * np.hypot(b, t))


def test_thin_scaling_thickens_a_flat_bar_across_its_thickness_only():
    v, f, sk, w = plate()
    before = osteon.analyze(v, f, sk, w, force=10.0)
    mid = np.argmin(np.abs(before.section_param - 50.0))
    assert before.section_aspect[mid] == pytest.approx(4.0, rel=1e-9)  # width / thickness
    assert abs(before.section_thin_axis[mid] @ [0, 0, 1]) == pytest.approx(1.0, abs=1e-12)
    allowable = before.max_stress / 2
    thin = osteon.correct(v, f, sk, w, force=10.0, allowable_stress=allowable, scaling="thin")
    both = osteon.correct(v, f, sk, w, force=10.0, allowable_stress=allowable,
                          scaling="uniform")
    assert thin.converged and both.converged and not thin.after.weak.any()
    # first round: sqrt of the stress ratio (a plate's W grows as t^2), on one axis only
    assert thin.rounds[0][1] == pytest.approx(np.sqrt(2 / 0.99), rel=1e-9)
    assert {r[3] for r in thin.rounds} == {1} and len(thin.rounds) <= 3
    assert abs(thin.bone_x_axis[0] @ [0, 0, 1]) == pytest.approx(1.0, abs=1e-12)
    assert thin.bone_scale_z[0] == 1.0
    # width and length untouched (bitwise); the thickness grows by the x scale
    assert np.array_equal(thin.vertices[:, :2], v[:, :2])
    assert np.allclose(thin.vertices[:, 2], thin.bone_scale_x[0] * v[:, 2])
    # the stress after is the closed form for a 12 x (3 s) rectangle
    s = thin.bone_scale_x[0]
    w_after = rectangle_modulus(12.0, 3.0 * s)
    assert thin.after.section_modulus[mid] == pytest.approx(w_after, rel=1e-9)
    # less material than scaling both axes (area x s vs x s^2), and narrower
    assert thin.volume_change_percent == pytest.approx(100 * (s - 1), rel=1e-6)
    assert thin.volume_change_percent < both.volume_change_percent
    assert np.ptp(thin.vertices[:, 1]) < np.ptp(both.vertices[:, 1])
    # skin() reproduces it from the reported scales and axes
    again = osteon.skin(v, sk, w, thin.bone_scale_x, bone_scale_z=thin.bone_scale_z,
                        bone_x_axes=thin.bone_x_axis)
    assert np.allclose(again, thin.vertices, atol=1e-12)


def test_thin_scaling_uses_the_given_bone_axes():
    """With Blender's bone axes given (x across the width), the thickness is the z axis."""
    v, f, sk, w = plate()
    allowable = osteon.analyze(v, f, sk, w, force=10.0).max_stress / 2
    free = osteon.correct(v, f, sk, w, force=10.0, allowable_stress=allowable, scaling="thin")
    given = osteon.correct(v, f, sk, w, force=10.0, allowable_stress=allowable, scaling="thin",
                           bone_x_axes=[[0, 1, 0]])
    assert {r[3] for r in given.rounds} == {2}
    assert given.bone_scale_x[0] == 1.0 and given.bone_scale_z[0] == free.bone_scale_x[0]
    assert np.allclose(given.vertices, free.vertices, atol=1e-12)
    # an axis 45 degrees off the thickness cannot be reproduced: both axes are scaled instead
    tilted = osteon.correct(v, f, sk, w, force=10.0, allowable_stress=allowable,
                            scaling="thin", bone_x_axes=[[0, 1, 1]])
    assert {r[3] for r in tilted.rounds} == {0} and tilted.converged


def test_thin_scaling_leaves_round_parts_to_both_axes():
    v, f, sk, w = bar()
    allowable = osteon.analyze(v, f, sk, w, force=10.0).max_stress / 2
    thin = osteon.correct(v, f, sk, w, force=10.0, allowable_stress=allowable, scaling="thin")
    both = osteon.correct(v, f, sk, w, force=10.0, allowable_stress=allowable,
                          scaling="uniform")
    assert np.array_equal(thin.vertices, both.vertices)
    assert np.array_equal(thin.bone_scale_x, thin.bone_scale_z)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [({"scaling": "thinner"}, "scaling must be"),
     ({"flat_aspect": 0.5}, "flat_aspect"),
     ({"bone_x_axes": [[0, 1, 0], [0, 1, 0]]}, "bone_x_axes must have shape"),
     ({"bone_x_axes": [[1, 0, 0]]}, "across the bone"),
     ({"bone_x_axes": [[0, np.nan, 1]]}, "NaN")],
)
def test_bad_scaling_arguments(kwargs, message):
    v, f, sk, w = plate()
    with pytest.raises(ValueError, match=message):
        osteon.correct(v, f, sk, w, force=10.0, allowable_stress=1.0, **kwargs)


def test_skin_axis_scales_need_axes():
    v, _f, sk, w = plate()
    with pytest.raises(ValueError, match="bone_x_axes"):
        osteon.skin(v, sk, w, [1.0], bone_scale_z=[2.0])


@pytest.mark.parametrize("scaling", ["uniform", "thin"])
@pytest.mark.parametrize("name", ["arm", "elephant", "cheburashka", "cow", "rignet2982",
                                  "rignet11814"])
def test_real_models_converge_under_a_load_that_makes_them_weak(name, scaling, data_dir):
    """The scaling loop on the beam stresses (notch_sensitivity=0): with the corner model on,
    a corner at a joint whose sections lie under blended weights can stop the loop ("scaling
    does not thicken it"; the elephant's bone_4/bone_5, docs/notch.md), which
    test_the_corner_model_stops_with_its_reason checks."""
    v, f, sk, w = load(name, height_mm=120.0)
    before = osteon.analyze(v, f, sk, w, force=20.0, notch_sensitivity=0.0)
    allowable = before.max_stress / 2  # twice over the limit somewhere
    fix = osteon.correct(v, f, sk, w, force=20.0, allowable_stress=allowable, scaling=scaling,
                         notch_sensitivity=0.0)
    assert fix.before.weak.any()
    assert fix.converged, fix.reason
    assert not fix.after.weak.any()
    assert fix.after.max_stress <= allowable
    # only vertices with weight on a scaled bone moved
    scaled = np.flatnonzero(fix.bone_scale != 1.0)
    touched = np.asarray(w[:, scaled].sum(axis=1)).ravel() > 0
    assert np.array_equal(fix.vertices[~touched], v[~touched])


def test_the_corner_model_stops_with_its_reason(data_dir):
    """With the corner model (q = 1) the elephant's loop ends on joint sections that scaling
    cannot thicken, and says so by bone; every section it leaves weak is named."""
    v, f, sk, w = load("elephant", height_mm=120.0)
    before = osteon.analyze(v, f, sk, w, force=20.0, notch_sensitivity=0.0)
    fix = osteon.correct(v, f, sk, w, force=20.0, allowable_stress=before.max_stress / 2)
    if fix.converged:
        assert not fix.after.weak.any()
    else:
        assert "cannot be fixed by scaling" in fix.reason
        named = {fix.after.bone_names[fix.after.section_bone[s]] for s in fix.unfixed_sections}
        assert named and all(f"bone '{b}'" in fix.reason for b in named)
        # every section left weak is one the reason lists, and it is a corner or a joint one
        assert set(np.flatnonzero(fix.after.weak)) <= set(fix.unfixed_sections)
