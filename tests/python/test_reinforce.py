"""osteon.reinforce: more walls and infill where the printed part is weak (issue 32). Closed
forms from the printed section (docs/printing.md) and the modifier volumes' geometry; meshes made
here. The slicer's side (the G-code of the exported project) is in test_slicer3mf.py."""

from __future__ import annotations

import numpy as np
import osteon
import pytest
import trimesh
from osteon.reinforcement import convex_volume, modifier_volume, vertex_stress, weak_regions
from shapes import cylinder_along, merge


def _l_shape():
    """An L: a 40 mm arm r = 4 along +x and a 40 mm post r = 3 rising at its end (bone b)."""
    v, f = merge(cylinder_along((0, 0, 0), (40, 0, 0), 4.0),
                 cylinder_along((40, 0, -4), (40, 0, 40), 3.0))
    sk = osteon.Skeleton([[0, 0, 0], [40, 0, 0]], [[40, 0, 0], [40, 0, 36]], [-1, 0], ["a", "b"])
    return v, f, sk


def _inside(v, f, pts, tol=1e-9):
    """Points inside a closed convex mesh with outward faces (every face plane in front)."""
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    n = np.cross(b - a, c - a)
    return np.all(np.einsum(
        "pfk,fk->pf", pts[:, None, :] - a[None], n) <= tol * np.linalg.norm(n, axis=1), axis=1)


def test_modifier_volume_is_closed_and_encloses_the_weak_span():
    v, f, sk = _l_shape()
    # 14 MPa: the post's lower sections (17.2 .. 14.3 MPa under 10 N) are weak, the arm is not.
    # Beam stresses (notch_sensitivity=0): the L's sharp inner corner makes its 45° joint section
    # weak too (Kt 2.2 since the corner finder's sectors turn with the model), which would take
    # the region round the corner; this test is about the volume of a straight weak span.
    a = osteon.analyze(v, f, sk, force=10, allowable_stress=14, interval=2, keep_outlines=True,
                       notch_sensitivity=0.0)
    (region,) = weak_regions(a)
    assert set(a.section_bone[region]) == {1}
    assert len(region) == int(a.weak.sum()) >= 3
    mv, mf = modifier_volume(a, region, margin=1.0)
    mesh = trimesh.Trimesh(mv, mf, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume > 0
    inside = np.concatenate([lp for s in region for lp in a.section_loops[s]])
    assert _inside(mv, mf, inside).all()
    # half an interval beyond the end sections along the bone, and the margin around it
    z = a.section_center[region, 2]
    lo, hi = mesh.bounds
    assert lo[2] == pytest.approx(z.min() - 1.0 - 1.0, abs=0.05)
    assert hi[2] == pytest.approx(z.max() + 1.0 + 1.0, abs=0.05)
    assert 2 * (3.0 + 0.92) < hi[0] - lo[0] < 2 * (3.0 + 1.0) + 0.2  # 26 directions: see below
    # the arm beyond one interval + margin from the post is not inside
    arm = np.concatenate([lp for s in np.flatnonzero((a.section_bone == 0)
                                                     & (a.section_param < 34))
                          for lp in a.section_loops[s]])
    assert not _inside(mv, mf, arm).any()


def test_convex_volume_grows_by_the_margin():
    # a 2 mm cube grown by r: V + S r + 6 pi r^2 + 4/3 pi r^3 (Steiner); the 26 growth
    # directions reach at least 0.92 r everywhere, at most r
    cube = np.array([(x, y, z) for x in (0, 2) for y in (0, 2) for z in (0, 2)], float)
    v, f = convex_volume(cube, margin=0.5)
    mesh = trimesh.Trimesh(v, f, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent

    def steiner(r):
        return 8 + 24 * r + 6 * np.pi * r**2 + 4 / 3 * np.pi * r**3

    assert steiner(0.92 * 0.5) < mesh.volume <= steiner(0.5)
    assert _inside(v, f, cube).all()
    assert not _inside(v, f, np.array([[1.0, 1.0, 2.6], [-0.6, 1.0, 1.0]])).any()


# --------------------------------------------------------------------------- the search

R, LINE, LAYER = 5.0, 0.45, 0.2


def _rod(length=44.0):
    """A round rod r = 5 standing on +z from z = -4 to ``length``; its bone from z = 0 to
    ``length`` - 4 (every section is a plain cut, none at a cap). The build direction is +z, so
    every section is a layer: walls all round, no skins (docs/printing.md)."""
    v, f = cylinder_along((0, 0, -4), (0, 0, length), R, n=96, stations=48)
    sk = osteon.Skeleton([[0, 0, 0]], [[0, 0, length - 4]], [-1], ["rod"])
    return v, f, sk


def _fdm(perimeters=2, infill=0.0):
    # 0 % infill: the printed section is a tube; no small-area rule (a 78 mm² rod would be
    # filled solid at PrusaSlicer's 70 mm²)
    return osteon.PrintProfile.fdm(perimeters=perimeters, line_width=LINE, layer_height=LAYER,
                                   top_bottom_layers=4, infill=infill, pattern="gyroid",
                                   solid_infill_below_area=0.0)


def _wall_depth(p):
    """PrusaSlicer's wall depth w/2 + s/2 + (P - 1) s, s = w - h (1 - pi/4) (osteon.printed)."""
    s = LINE - LAYER * (1 - np.pi / 4)
    return LINE / 2 + s / 2 + (p - 1) * s


def _tube_w(p):
    """Section modulus of the printed rod with P perimeters and no infill: a tube, mm³."""
    ri = R - _wall_depth(p)
    return np.pi * (R**4 - ri**4) / (4 * R)


KW = {"force": 10.0, "interval": 2.0}


def test_the_load_does_not_depend_on_the_print():
    # why re-analysing the whole part per candidate is exact: only W changes with the profile
    v, f, sk = _rod()
    a = osteon.analyze(v, f, sk, allowable_stress=30, print_profile=_fdm(2), **KW)
    b = osteon.analyze(v, f, sk, allowable_stress=30, print_profile=_fdm(7, 0.4), **KW)
    c = osteon.analyze(v, f, sk, allowable_stress=30, **KW)  # solid
    np.testing.assert_array_equal(a.moment, b.moment)
    np.testing.assert_array_equal(a.moment, c.moment)
    assert np.all(b.section_modulus[b.valid] > a.section_modulus[a.valid])


@pytest.mark.parametrize("n", [4, 7])
def test_a_rod_that_needs_n_perimeters_gets_n(n):
    v, f, sk = _rod()
    probe = osteon.analyze(v, f, sk, allowable_stress=30, print_profile=_fdm(2), **KW)
    ok = probe.valid
    # the closed form of the printed section (a tube of the wall depth) is what the engine has
    np.testing.assert_allclose(probe.section_modulus[ok], _tube_w(2), rtol=0.01)
    m = np.max(np.abs(probe.moment[ok]))
    s_fewer, s_n = m / _tube_w(n - 1), m / _tube_w(n)
    allowable = 0.5 * (s_fewer + s_n)  # N - 1 walls are not enough, N are
    r = osteon.reinforce(v, f, sk, allowable_stress=allowable, print_profile=_fdm(2), **KW)
    assert len(r.regions) == 1 and not r.unfixable
    (g,) = r.regions
    assert (g["perimeters"], g["infill"], g["fixed"]) == (n, 0.0, True)
    # the region is every section weak with 2 walls; after, none is weak
    np.testing.assert_array_equal(np.sort(g["sections"]),
                                  np.flatnonzero(ok & (probe.stress > allowable)))
    assert not r.after.weak.any() and r.after.max_stress <= allowable
    # the colours follow: no vertex over the allowable after, the engine's rule before
    assert r.after.vertex_stress.max() <= allowable
    np.testing.assert_allclose(vertex_stress(r.before, v, [0], np.zeros(len(v))),
                               r.before.vertex_stress, rtol=2e-6)  # the engine stores float32
    # re-analysed with the region's settings: under the allowable in every section
    check = osteon.analyze(v, f, sk, allowable_stress=allowable, print_profile=_fdm(n), **KW)
    assert np.all(check.stress[g["sections"]] <= allowable)
    np.testing.assert_allclose(r.after.stress[g["sections"]], check.stress[g["sections"]])
    # cost: the extra wall area of each section (tube areas) x the interval
    wall = lambda p: np.pi * (R**2 - (R - _wall_depth(p)) ** 2)
    expected = (wall(n) - wall(2)) * KW["interval"] * len(g["sections"])
    assert g["extra_volume_mm3"] == pytest.approx(expected, rel=0.01)


def test_infill_after_walls_and_unfixable_when_solid_is_not_enough():
    v, f, sk = _rod()
    solid = osteon.analyze(v, f, sk, allowable_stress=30, **KW)
    m = np.max(np.abs(solid.moment[solid.valid]))
    w_solid = np.max(solid.section_modulus[solid.valid])
    # 3 walls max: a tube of 3 walls cannot, the solid rod can (-> infill, at most solid)
    allowable = 0.5 * (m / _tube_w(3) + m / w_solid)
    r = osteon.reinforce(v, f, sk, allowable_stress=allowable, print_profile=_fdm(2),
                         max_perimeters=3, **KW)
    (g,) = r.regions
    assert g["fixed"] and g["infill"] > 0.0 and not r.unfixable
    assert not r.after.weak.any()
    # the fewest walls at that infill: one fewer wall does not hold
    if g["perimeters"] > 2:
        fewer = osteon.analyze(v, f, sk, allowable_stress=allowable,
                               print_profile=_fdm(g["perimeters"] - 1, g["infill"]), **KW)
        assert fewer.weak[g["sections"]].any()
    # below what solid carries: the sections over it are unfixable, with their solid stress
    low = 0.9 * solid.max_stress
    r = osteon.reinforce(v, f, sk, allowable_stress=low, print_profile=_fdm(2), **KW)
    over = np.flatnonzero(solid.valid & (solid.stress > low))
    assert sorted(u["section"] for u in r.unfixable) == over.tolist()
    for u in r.unfixable:
        assert u["stress_mpa"] == pytest.approx(solid.stress[u["section"]])
        assert u["bone"] == "rod"
    assert not r.regions[0]["fixed"] and r.regions[0]["infill"] == 1.0


def test_reinforce_first_thickens_only_what_solid_cannot_carry():
    v, f, sk = _rod()
    solid = osteon.analyze(v, f, sk, allowable_stress=30, **KW)
    # walls are enough: the shape is not touched
    m = np.max(np.abs(solid.moment[solid.valid]))
    fix = osteon.correct(v, f, sk, None, allowable_stress=m / _tube_w(4) * 1.01,
                         print_profile=_fdm(2), reinforce_first=True, **KW)
    assert fix.converged and np.all(fix.bone_scale == 1.0)
    np.testing.assert_array_equal(fix.vertices, v)
    assert fix.reinforcement.regions[0]["perimeters"] == 4
    # solid is not enough: thickened, then reinforced; nothing weak after
    fix = osteon.correct(v, f, sk, None, allowable_stress=0.8 * solid.max_stress,
                         print_profile=_fdm(2), reinforce_first=True, **KW)
    assert fix.bone_scale[0] > 1.0 and fix.converged
    assert not fix.after.weak.any()
    assert fix.reinforcement is not None and not fix.reinforcement.unfixable


def test_reinforce_rejects_bad_input():
    v, f, sk = _rod()
    with pytest.raises(ValueError, match="FDM"):
        osteon.reinforce(v, f, sk, allowable_stress=30, print_profile="solid", **KW)
    with pytest.raises(ValueError, match="max_perimeters"):
        osteon.reinforce(v, f, sk, allowable_stress=30, print_profile=_fdm(), max_perimeters=0,
                         **KW)
