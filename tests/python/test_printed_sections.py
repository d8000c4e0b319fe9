"""Sections as a slicer prints them (issue 12): overlapping shells merge, real holes stay, bones
outside the mesh take their own part's section, thin parts and loose pieces are reported apart.
Reference numbers from closed forms or an independent raster; meshes generated here."""

from __future__ import annotations

import numpy as np
import osteon
import pytest
from shapes import capsule_along, circle, cylinder_along, merge, prism, rectangle


def _bone(length, start=(0.0, 0.0, 0.0), direction=(1.0, 0.0, 0.0)):
    s = np.asarray(start, float)
    return osteon.Skeleton([s], [s + length * np.asarray(direction, float)], [-1], ["b"])


def _poly_area(p):
    x, y = p[:, 0], p[:, 1]
    return 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def _interior(a):
    return (a.section_kind == 0) & a.valid


def test_inner_shell_adds_nothing():
    outer, inner = circle(5, 64), circle(2, 64)
    v, f = merge(prism(outer, 40), prism(inner, 40))
    a = osteon.analyze(v, f, _bone(40), interval=4)
    i = _interior(a)
    assert i.sum() > 5
    np.testing.assert_allclose(a.section_area[i], _poly_area(outer), rtol=1e-9)  # 78.4 mm²
    assert abs(_poly_area(outer) - 78.41) < 0.01
    assert not np.any(a.section_flags[i] & osteon.SECTION_FLAGS["hollow"])


def test_real_tube_keeps_its_hole():
    outer, inner = circle(5, 64), circle(2, 64)
    v, f = prism(outer, 40, hole=inner)
    a = osteon.analyze(v, f, _bone(40), interval=4)
    i = _interior(a)
    np.testing.assert_allclose(a.section_area[i], _poly_area(outer) - _poly_area(inner),
                               rtol=1e-9)


def test_two_offset_cylinders_give_the_union():
    # Two closed r = 5 cylinders 4 mm apart; the bone runs along the first one's axis.
    c = circle(5, 64)
    v1, f1 = prism(c, 40)
    v2, f2 = prism(c, 40)
    v2 = v2 + [0.0, 4.0, 0.0]
    v, f = merge((v1, f1), (v2, f2))
    a = osteon.analyze(v, f, _bone(40), interval=4)
    i = _interior(a)
    # Independent reference: a 1200 x 1200 raster of the union of the two 64-gons.
    n = 1200
    ys = np.linspace(-5.5, 9.5, n)
    zs = np.linspace(-5.5, 5.5, n)
    yy, zz = np.meshgrid(ys, zs)
    pts = np.stack([yy.ravel(), zz.ravel()], 1)

    def inside(poly, p):
        # convex CCW polygon: left of every edge
        ok = np.ones(len(p), bool)
        for a, b in zip(poly, np.roll(poly, -1, 0)):
            ok &= (b[0] - a[0]) * (p[:, 1] - a[1]) - (b[1] - a[1]) * (p[:, 0] - a[0]) >= 0
        return ok

    mask = inside(c, pts) | inside(c + [4.0, 0.0], pts)
    cell = (ys[1] - ys[0]) * (zs[1] - zs[0])
    area = mask.sum() * cell
    np.testing.assert_allclose(a.section_area[i], area, rtol=3e-3)
    assert abs(area - 117.3) < 0.3  # the 117.5 mm² for circles, a 64-gon slightly less
    # modulus about the weakest direction, from the raster's moments
    p = pts[mask]
    cen = p.mean(0)
    d = p - cen
    j = np.array([[np.sum(d[:, 0] ** 2), np.sum(d[:, 0] * d[:, 1])],
                  [np.sum(d[:, 0] * d[:, 1]), np.sum(d[:, 1] ** 2)]]) * cell
    w = 1.0 / np.max(np.linalg.norm(np.linalg.solve(j, d.T), axis=0))
    np.testing.assert_allclose(a.section_modulus[i], w, rtol=1e-2)


def test_outside_bone_takes_its_own_part_not_a_sliver():
    # Bone 1 (the shin) leaves its leg at the knee: it runs beside its own r = 5 cylinder, and a
    # thin r = 0.4 strap of bone 0 passes nearer its path. Its sections are the leg's own cut.
    leg = cylinder_along((0, -8, 0), (40, -8, 0), 5.0)
    strap = cylinder_along((0, 1.5, 0), (40, 1.5, 0), 0.4, n=16)
    v, f = merge(leg, strap)
    sk = osteon.Skeleton([[0, 0, 0], [0, 20, 0]], [[40, 0, 0], [0, 30, 0]], [-1, 0],
                         ["shin", "other"])
    w = np.zeros((len(v), 2))
    w[: len(leg[0]), 0] = 1.0
    w[len(leg[0]):, 1] = 1.0
    # The strap is weighted to the other bone; the shin bone owns the leg.
    a = osteon.analyze(v, f, sk, w, interval=4)
    i = (a.section_bone == 0) & (a.section_kind == 0)
    assert np.all(a.section_flags[i] & osteon.SECTION_FLAGS["outside"])
    np.testing.assert_allclose(a.section_area[i], np.pi * 25, rtol=0.01)
    assert np.all(np.abs(a.section_center[i][:, 1] + 8) < 1e-6)


def test_no_region_of_the_bone_is_unreliable_and_left_out():
    # Bone 1 runs beside a cylinder it owns no part of: unreliable, NaN, not in the maximum.
    v, f = cylinder_along((0, 0, 0), (40, 0, 0), 5.0)
    sk = osteon.Skeleton([[0, 0, 0], [20, 8, 0]], [[40, 0, 0], [20, 8, 30]], [-1, 0],
                         ["body", "prop"])
    w = np.zeros((len(v), 2))
    w[:, 0] = 1.0
    a = osteon.analyze(v, f, sk, w, interval=4)
    doubt = a.unreliable
    assert doubt.any()
    assert np.all(np.isnan(a.stress[doubt]))
    assert not a.weak[doubt].any() and not a.culled[doubt].any()
    assert a.weakest_section >= 0 and not doubt[a.weakest_section]
    reasons = a.flag_reasons(int(np.flatnonzero(doubt)[0]))
    assert any("no part here belongs to it" in r for r in reasons)


def test_too_thin_plate_is_reported_apart():
    # A 20 x 0.4 mm plate: thickness 0.4 mm (the minimum width), below 0.8 mm.
    v, f = prism(rectangle(20, 0.4), 40)
    a = osteon.analyze(v, f, _bone(40), interval=4, allowable_stress=1e-6)
    i = _interior(a)
    np.testing.assert_allclose(a.section_thickness[i], 0.4, rtol=1e-9)
    assert np.all(a.too_thin[i])
    assert not a.weak.any()  # reported apart from the overloaded ones
    assert a.flag_reasons(int(np.flatnonzero(i)[0]))[-1] == "too thin to print (0.4 mm < 0.8 mm)"
    # Resin prints it: min_thickness 0.3 mm.
    b = osteon.analyze(v, f, _bone(40), interval=4, allowable_stress=1e-6, min_thickness=0.3)
    assert not b.too_thin.any() and b.weak[_interior(b)].all()
    with pytest.raises(ValueError, match="min_thickness"):
        osteon.analyze(v, f, _bone(40), min_thickness=-1)


def test_round_section_thickness_is_its_diameter():
    v, f = prism(circle(5, 256), 40)
    a = osteon.analyze(v, f, _bone(40), interval=4)
    i = _interior(a)
    np.testing.assert_allclose(a.section_thickness[i], 10 * np.cos(np.pi / 256), rtol=1e-9)


def test_loose_pieces_are_listed():
    body = prism(circle(5, 64), 40)
    eye = cylinder_along((10, 0, 0), (14, 0, 0), 2.0, n=16, stations=4)  # inside the body
    prop = cylinder_along((10, 30, 0), (20, 30, 0), 2.0, n=16, stations=4)  # floating apart
    v, f = merge(body, eye, prop)
    a = osteon.analyze(v, f, _bone(40), interval=4)
    assert len(a.loose_pieces) == 1
    start = len(body[0]) + len(eye[0])
    np.testing.assert_array_equal(np.sort(a.loose_pieces[0]), np.arange(start, len(v)))
    v1, f1 = merge(body, eye)
    assert osteon.analyze(v1, f1, _bone(40), interval=4).loose_pieces == []


def test_a_face_of_one_vertex_thrice_is_no_triangle():
    # Found by the API fuzz test under ASan: a "face" (v, v, v) of a vertex in no other face, in
    # a mesh of several shells, was written before the first shell's face list (heap
    # corruption; a crash). It is no triangle: the vertex is in no shell, the prop is still the
    # one loose piece, and the analysis equals the one without that face, wherever it comes.
    body = prism(circle(5, 64), 40)
    prop = cylinder_along((10, 30, 0), (20, 30, 0), 2.0, n=16, stations=4)  # floating apart
    v, f = merge(body, prop)
    v = np.vstack([v, [[0.0, 20.0, 0.0]]])  # the stray vertex
    stray = len(v) - 1
    plain = osteon.analyze(v, f, _bone(40), interval=4)
    assert len(plain.loose_pieces) == 1
    for faces in (np.vstack([f, [[stray] * 3]]), np.vstack([[[stray] * 3], f])):
        a = osteon.analyze(v, faces, _bone(40), interval=4)
        np.testing.assert_array_equal(a.loose_pieces[0], plain.loose_pieces[0])
        np.testing.assert_array_equal(a.stress, plain.stress)


def test_loose_piece_is_no_load_point():
    # A 4 x 4 mm bar along x (0..40 mm) and, far beyond its end, a detached ball-like capsule
    # (x = 70..74 mm): it falls off the print, so it carries no load. Each section's moment is
    # F times the distance from its centroid to the bar's farthest corner (x = 40, y = z = ±2).
    bar = prism(rectangle(4, 4), 40)
    ball = cylinder_along((70, 0, 0), (74, 0, 0), 2.0, n=16, stations=4)
    v, f = merge(bar, ball)
    force = 20.0
    a = osteon.analyze(v, f, _bone(40), interval=4, force=force)
    bar_only = osteon.analyze(*bar, _bone(40), interval=4, force=force)
    assert len(a.loose_pieces) == 1
    np.testing.assert_array_equal(np.sort(a.loose_pieces[0]), np.arange(len(bar[0]), len(v)))
    i = _interior(a)
    assert i.sum() > 5
    c = a.section_center[i]
    d = np.sqrt((40 - c[:, 0]) ** 2 + (2 + np.abs(c[:, 1])) ** 2 + (2 + np.abs(c[:, 2])) ** 2)
    np.testing.assert_allclose(a.moment[i], force * d, rtol=1e-9)
    np.testing.assert_allclose(a.moment, bar_only.moment, rtol=1e-12)
    # the load points are bar corners, never the loose piece
    assert np.all(a.load_point[:, 0] <= 40 + 1e-9)
    # the loose piece keeps no stress (it is not analysed as if attached)
    assert np.all(a.vertex_stress[len(bar[0]):] == 0)
    np.testing.assert_allclose(a.vertex_stress[:len(bar[0])], bar_only.vertex_stress, rtol=1e-12)


def test_reused_analyzer_finds_loose_pieces_as_a_fresh_analysis():
    # Live mode: one Analyzer, faces fixed, the capsule moved between runs: beyond the bar's end
    # (loose: the moment is that of the bar alone), inside the bar (attached), and beyond again.
    # Each run equals a fresh analysis of the same vertices (the kept search forgets the last
    # run's pieces).
    bar = prism(rectangle(4, 4), 40)
    ball = cylinder_along((70, 0, 0), (74, 0, 0), 2.0, n=16, stations=4)
    v, f = merge(bar, ball)
    start = len(bar[0])
    an = osteon.Analyzer(f, len(v), _bone(40), interval=4, force=20.0)
    bar_only = osteon.analyze(*bar, _bone(40), interval=4, force=20.0)
    for shift, loose in ((0.0, True), (-50.0, False), (10.0, True)):
        moved = v.copy()
        moved[start:, 0] += shift
        again = an.run(moved)
        fresh = osteon.analyze(moved, f, _bone(40), interval=4, force=20.0)
        assert [list(p) for p in again.loose_pieces] == [list(p) for p in fresh.loose_pieces]
        assert len(again.loose_pieces) == int(loose)
        np.testing.assert_array_equal(again.moment, fresh.moment)
        np.testing.assert_array_equal(again.vertex_stress, fresh.vertex_stress)
        if loose:
            np.testing.assert_allclose(again.moment, bar_only.moment, rtol=1e-12)


@pytest.mark.parametrize(("inner", "expect"), [
    (4.0, np.cos(np.pi / 64)),  # a tube r 5 / r 4: its wall (parallel 64-gon edges cos(π/64) apart)
    (None, 10 * np.cos(np.pi / 64)),  # a solid round: its diameter (across flats)
])
def test_thickness_of_a_hollow_wall(inner, expect):
    outer = circle(5, 64)
    mesh = prism(outer, 40) if inner is None else prism(outer, 40, hole=circle(inner, 64))
    a = osteon.analyze(*mesh, _bone(40), interval=4, min_thickness=0)
    i = _interior(a)
    np.testing.assert_allclose(a.section_thickness[i], expect, rtol=1e-9)
    # a 1 mm wall is thick enough for FDM (0.8 mm), too thin for a 1.5 mm minimum
    thin = osteon.analyze(*mesh, _bone(40), interval=4, min_thickness=1.5)
    assert bool(np.all(thin.section_flags[i] & osteon.SECTION_FLAGS["too_thin"])) == (
        inner is not None)


def test_plate_thickness():
    a = osteon.analyze(*prism(rectangle(30, 0.6), 40), _bone(40), interval=4, min_thickness=0)
    np.testing.assert_allclose(a.section_thickness[_interior(a)], 0.6, rtol=1e-9)


def _segment_distance(p, a, b):
    ab = b - a
    t = np.clip(((p - a) @ ab) / (ab @ ab), 0, 1)
    return np.linalg.norm(p - (a + t[:, None] * ab), axis=1)


def test_bent_knee_section_is_the_capsules_cut():
    # A leg bent at the knee: thigh capsule hip (0,0,60) -> knee (15,0,30), shin capsule knee ->
    # ankle (0,0,0), r = 5 (two fused, overlapping shells). The bone runs straight from hip to
    # ankle along z and leaves the leg between z ~ 10 and 50 (the knee is 15 mm off it). Every
    # section must be the leg's own cut by its plane (the union of both capsules' cuts), never
    # a sliver and never unreliable; the reference is an independent raster of the two ideal
    # capsules' cut.
    hip, knee, ankle, r = np.array([0, 0, 60.0]), np.array([15, 0, 30.0]), np.zeros(3), 5.0
    v, f = merge(capsule_along(hip, knee, r), capsule_along(knee, ankle, r))
    sk = osteon.Skeleton([hip], [ankle], [-1], ["leg"])
    a = osteon.analyze(v, f, sk, interval=5, min_thickness=0)
    i = np.flatnonzero(a.section_kind == 0)
    assert len(i) >= 9
    n = 600
    xs = np.linspace(-8, 22, n)
    ys = np.linspace(-6, 6, 240)
    xx, yy = np.meshgrid(xs, ys)
    cell = (xs[1] - xs[0]) * (ys[1] - ys[0])
    knee_seen = False
    for s in i:
        z = a.section_point[s][2]
        pts = np.column_stack([xx.ravel(), yy.ravel(), np.full(xx.size, z)])
        inside = np.minimum(_segment_distance(pts, hip, knee), _segment_distance(pts, knee, ankle))
        want = np.count_nonzero(inside <= r) * cell
        assert not (a.section_flags[s] & osteon.SECTION_FLAGS["unreliable"]), z
        # within a few % (the mesh is a 64-gon with 12 cap rings; the raster cell is 0.05 mm)
        assert a.section_area[s] == pytest.approx(want, rel=0.03), z
        if abs(z - 30) < 1e-6:
            knee_seen = True
            assert a.section_flags[s] & osteon.SECTION_FLAGS["outside"]  # the bone is off the leg
            assert a.section_area[s] > 0.9 * np.pi * r**2  # not a sliver
    assert knee_seen


def test_plate_through_a_body_is_attached():
    # A thin plate (0.4 x 120 x 1 mm) pushed through a closed r = 5 body between two of its
    # vertex rings: no vertex of either lies inside the other, but their surfaces cross, so the
    # plate is held (not loose) and its far corners load the body's sections.
    body = prism(circle(5, 64), 40)
    pv, pf = prism(rectangle(120, 1), 0.4, stations=2)
    plate = (pv + [18.3, 0.0, 0.0], pf)
    v, f = merge(body, plate)
    a = osteon.analyze(v, f, _bone(40), interval=4)
    assert a.loose_pieces == []
    far = np.flatnonzero(_interior(a) & (a.section_param < 18))
    assert len(far) > 2 and np.all(np.abs(a.load_point[far, 1]) > 59)  # the plate's corners


def test_a_gap_narrower_than_the_printer_resolves_is_attached():
    # A 4 x 4 mm bar (x = 0..40 mm) and a capsule-like cap 0.3 mm beyond its end face. A printer
    # fuses a gap narrower than half its minimum printable thickness: PLA's 0.8 mm gives 0.4 mm,
    # so the cap is attached and loads the bar; at min_thickness 0.5 mm (gap 0.25 mm) it is a
    # loose piece and the bar is loaded at its own corners.
    bar = prism(rectangle(4, 4), 40)
    cap = cylinder_along((40.3, 0, 0), (44.3, 0, 0), 1.5, n=16, stations=4)
    v, f = merge(bar, cap)
    force = 20.0
    fused = osteon.analyze(v, f, _bone(40), interval=4, force=force, min_thickness=0.8)
    apart = osteon.analyze(v, f, _bone(40), interval=4, force=force, min_thickness=0.5)
    assert fused.loose_pieces == []
    assert len(apart.loose_pieces) == 1
    np.testing.assert_array_equal(np.sort(apart.loose_pieces[0]), np.arange(len(bar[0]), len(v)))
    i = _interior(fused)
    assert i.sum() > 5
    # the moment arm is the distance from the section's centroid to the farthest cap vertex
    # (computed here from the vertices), and beyond the bar's corners
    c = fused.section_center[i]
    cap_v = np.asarray(cap[0], dtype=float)
    d_cap = np.linalg.norm(cap_v[None, :, :] - c[:, None, :], axis=2).max(axis=1)
    np.testing.assert_allclose(fused.moment[i], force * d_cap, rtol=1e-9)
    d_bar = np.sqrt((40 - c[:, 0]) ** 2 + (2 + np.abs(c[:, 1])) ** 2 + (2 + np.abs(c[:, 2])) ** 2)
    np.testing.assert_allclose(apart.moment[i], force * d_bar, rtol=1e-9)
    assert np.all(fused.moment[i] > apart.moment[i])


def test_thickness_is_computed_on_first_read_and_survives_pickling():
    """The engine defers the thickness of sections whose too_thin check a lower bound decides;
    Analysis.section_thickness computes them on first read: the same numbers (a tube's wall, a
    plate's thickness, a 64-gon's width across flats), too_thin exactly where thickness < the
    minimum, and a pickled Analysis carries them."""
    import pickle

    tube = prism(circle(5, 64), 40, hole=circle(4, 64))
    for mesh, expect, minimum in ((prism(circle(5, 64), 40), 10 * np.cos(np.pi / 64), 0.8),
                                  (prism(rectangle(30, 0.6), 40), 0.6, 0.8),
                                  (tube, np.cos(np.pi / 64), 0.9),
                                  (tube, np.cos(np.pi / 64), 1.1)):
        a = osteon.analyze(*mesh, _bone(40), interval=4, min_thickness=minimum)
        i = _interior(a)
        thin = (a.section_flags & osteon.SECTION_FLAGS["too_thin"]) != 0
        # only too-thin sections were computed at once; the others wait for the first read
        assert (a.thickness_pending is None) == bool(thin[a.valid].all())
        b = pickle.loads(pickle.dumps(a))
        for r in (a, b):
            assert r.thickness_pending is None or r is a
            np.testing.assert_allclose(r.section_thickness[i], expect, rtol=1e-9)
            np.testing.assert_array_equal(thin[a.valid], r.section_thickness[a.valid] < minimum)
        assert a.thickness_pending is None  # read once: filled in, the regions released


def test_shells_sharing_positions_are_one_piece():
    """An unwelded seam joins two shells: a bar split at x = 12 mm into two face sets whose seam
    vertices are separate copies at the same positions is one piece (the big part's seam finds
    the small part's copies among the other shells' sorted positions); the same small part moved
    30 mm aside shares no position and is listed loose, with exactly its vertices."""
    v, f = prism(rectangle(4, 4), 40, stations=21)
    small = v[f].mean(axis=1)[:, 0] < 12
    used = np.unique(f[small])
    copy = {int(k): len(v) + i for i, k in enumerate(used)}
    f2 = f.copy()
    f2[small] = np.vectorize(copy.get)(f[small])
    v2 = np.vstack([v, v[used]])
    assert osteon.analyze(v2, f2, _bone(40), interval=4).loose_pieces == []
    apart = v2.copy()
    apart[len(v):, 1] += 30.0
    b = osteon.analyze(apart, f2, _bone(40), interval=4)
    assert len(b.loose_pieces) == 1
    np.testing.assert_array_equal(np.sort(b.loose_pieces[0]), np.arange(len(v), len(v2)))
