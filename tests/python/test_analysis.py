"""Analysis physics (docs/method.md) on procedural meshes with closed-form answers."""

import numpy as np
import osteon
import pytest
from shapes import circle, cylinder_along, l_section, merge, prism, rectangle, revolve

F = 10.0


def bar_skeleton(length):
    return osteon.Skeleton([[0, 0, 0]], [[length, 0, 0]], [-1], ["bar"])


def brute_force_arm(v, center, mask):
    return np.linalg.norm(v[mask] - center, axis=1).max()


@pytest.mark.parametrize(
    "name,profile,expected_w",
    [
        ("circle", circle(5.0, 256), np.pi * 5.0**3 / 4),
        ("square", rectangle(8.0, 8.0), 8.0**3 / (6 * np.sqrt(2))),
        ("rectangle", rectangle(12.0, 4.0), 144 * 16 / (6 * np.sqrt(144 + 16))),
    ],
)
def test_cantilever_stress_is_euler_bernoulli(name, profile, expected_w):
    length = 100.0
    v, f = prism(profile, length)
    res = osteon.analyze(v, f, bar_skeleton(length), force=F, interval=2.0)
    inner = (res.section_kind == 0) & (res.section_param > 5) & (res.section_param < 95)
    assert inner.sum() > 40
    assert np.all(res.section_flags[inner] == 0)
    # section modulus within 0.5 % of the exact value of the profile
    assert np.allclose(res.section_modulus[inner], expected_w, rtol=0.005)
    for i in np.flatnonzero(inner):
        c = res.section_center[i]
        assert abs(c[1]) < 1e-9 and abs(c[2]) < 1e-9 and abs(c[0] - res.section_param[i]) < 1e-9
        d = brute_force_arm(v, c, v[:, 0] >= res.section_param[i])
        assert res.moment_arm[i] == pytest.approx(d, rel=1e-12)
        # stress within 1 % of F d / W
        assert res.stress[i] == pytest.approx(F * d / expected_w, rel=0.01)


def test_tapered_limb_stress_grows_toward_the_hold():
    # A cone-like limb: thinner away from the hold, but the arm grows toward it: sigma = F d / W.
    xs = np.linspace(0, 80, 41)
    radii = 6.0 - 0.04 * xs
    v, f = revolve(xs, radii, 128)
    res = osteon.analyze(v, f, bar_skeleton(80.0), force=F, interval=4.0)
    inner = (res.section_kind == 0)
    for i in np.flatnonzero(inner):
        x = res.section_param[i]
        r = 6.0 - 0.04 * x
        w_polygon = np.pi * r**3 / 4
        assert res.section_modulus[i] == pytest.approx(w_polygon, rel=0.005)


def test_tube_with_bone_in_the_hollow_gets_the_whole_wall():
    ro, ri, length = 6.0, 4.0, 60.0
    v, f = prism(circle(ro, 256), length, hole=circle(ri, 256))
    res = osteon.analyze(v, f, bar_skeleton(length), force=F, interval=3.0)
    inner = (res.section_kind == 0) & (res.section_param > 3) & (res.section_param < 57)
    hollow = osteon.SECTION_FLAGS["hollow"]
    assert np.all(res.section_flags[inner] & hollow)
    ring = np.pi * (ro**2 - ri**2)
    assert np.allclose(res.section_area[inner], ring, rtol=0.001)
    assert np.allclose(res.section_modulus[inner], np.pi * (ro**4 - ri**4) / (4 * ro), rtol=0.005)


def test_l_section_bar_is_weak_in_its_unsymmetric_direction():
    v, f = prism(l_section(30, 20, 4), 80.0, fan_from=3)
    sk = osteon.Skeleton([[0, 8, 5]], [[80, 8, 5]], [-1])  # through the material near the corner
    res = osteon.analyze(v, f, sk, force=F, interval=4.0)
    from test_sections import l_section_modulus_by_rectangles

    expected, _, _ = l_section_modulus_by_rectangles(30, 20, 4)
    inner = (res.section_kind == 0) & (res.section_param > 4) & (res.section_param < 76)
    assert np.allclose(res.section_modulus[inner], expected, rtol=0.005)


def test_culling_and_weak_flags_are_consistent():
    # stepped shaft: thick, then thin
    xs = [0, 40, 40.001, 100]
    v, f = revolve(xs, [12, 12, 3, 3], 96)
    sk = bar_skeleton(100.0)
    res = osteon.analyze(v, f, sk, force=10.0, allowable_stress=20.0, interval=2.0)
    ok = res.valid
    assert res.max_moment == pytest.approx(res.moment[ok].max())
    assert res.safe_modulus == pytest.approx(res.max_moment / 20.0)
    assert np.array_equal(res.culled[ok], res.section_modulus[ok] > res.safe_modulus)
    assert np.array_equal(res.weak[ok], res.stress[ok] > 20.0)
    assert not np.any(res.culled & res.weak)
    assert res.culled.any() and res.weak.any()
    # the thick part is culled, the thin part near the step is the weakest
    thick = ok & (res.section_param < 38) & (res.section_kind == 0)
    assert res.culled[thick].all()
    assert 40 <= res.section_param[res.weakest_section] <= 44
    assert res.max_stress == pytest.approx(np.nanmax(res.stress))
    # per-vertex stress: the interpolation of the sections along the bone
    tip = np.flatnonzero((v[:, 0] > 60) & (v[:, 0] < 62))
    s = res.vertex_stress[tip]
    assert np.all(s > 0) and np.all(np.isfinite(s))
    grey = res.vertex_culled[(v[:, 0] > 5) & (v[:, 0] < 35)]
    assert grey.all()


def branching():
    """A trunk along x with two branches: one at the tail (+y), one at the middle (-y). Each
    branch starts 3 mm inside the trunk (r = 5): sunk into it, as game meshes are built, so it is
    held through the trunk (a detached branch would be a loose piece, no load)."""
    trunk = cylinder_along([0, 0, 0], [60, 0, 0], 5.0)
    tail_branch = cylinder_along([60, 2, 0], [60, 40, 0], 3.0)
    mid_branch = cylinder_along([30, -2, 0], [30, -30, 0], 3.0)
    v, f = merge(trunk, tail_branch, mid_branch)
    part = np.repeat([0, 1, 2], [len(trunk[0]), len(tail_branch[0]), len(mid_branch[0])])
    sk = osteon.Skeleton(
        [[0, 0, 0], [60, 0, 0], [30, 0, 0]], [[60, 0, 0], [60, 40, 0], [30, -30, 0]], [-1, 0, 0],
        ["trunk", "tail_branch", "mid_branch"],
    )
    return v, f, sk, part


def test_moment_arms_follow_the_downstream_rule():
    v, f, sk, part = branching()
    res = osteon.analyze(v, f, sk, force=F, interval=5.0)
    trunk = np.flatnonzero((res.section_bone == 0) & (res.section_kind == 0))
    assert len(trunk) > 8
    for i in trunk:
        x, c = res.section_param[i], res.section_center[i]
        downstream = ((part == 0) & (v[:, 0] >= x)) | (part == 1)  # tail branch attached at 60
        if x <= 30:
            downstream |= part == 2  # the middle branch attaches at 30: downstream only before it
        assert res.moment_arm[i] == pytest.approx(brute_force_arm(v, c, downstream), rel=1e-12), x
    # a section on the middle branch carries only that branch beyond it
    for i in np.flatnonzero((res.section_bone == 2) & (res.section_kind == 0)):
        c = res.section_center[i]
        t = res.section_param[i]
        mask = (part == 2) & (-v[:, 1] >= t)
        assert res.moment_arm[i] == pytest.approx(brute_force_arm(v, c, mask), rel=1e-12)


def test_holding_another_bone_reroots_the_tree():
    v, f, sk, part = branching()
    res = osteon.analyze(v, f, sk, force=F, interval=5.0, root="tail_branch")
    assert res.held_bone == 1
    for i in np.flatnonzero((res.section_bone == 0) & (res.section_kind == 0)):
        x, c = res.section_param[i], res.section_center[i]
        # held through the tail branch at x=60: downstream is toward the trunk's head
        downstream = ((part == 0) & (v[:, 0] < x)) | ((part == 2) if x >= 30 else False)
        assert res.moment_arm[i] == pytest.approx(brute_force_arm(v, c, downstream), rel=1e-12), x


def test_other_body_parts_in_the_same_plane_are_ignored():
    # a second bar beside the first, cut by the same planes
    a = prism(circle(4.0, 128), 50.0)
    b = prism(rectangle(6.0, 6.0), 50.0)
    b = (b[0] + [0, 30, 0], b[1])
    v, f = merge(a, b)
    res = osteon.analyze(v, f, bar_skeleton(50.0), force=F, interval=5.0)
    inner = (res.section_kind == 0)
    assert np.allclose(res.section_area[inner], osteon.section_properties(circle(4.0, 128))["area"])


def test_bone_outside_the_mesh_uses_the_nearest_loop_and_flags_it():
    v, f = prism(circle(4.0, 128), 50.0)
    sk = osteon.Skeleton([[0, 10, 0]], [[50, 10, 0]], [-1])  # 10 mm beside the bar
    res = osteon.analyze(v, f, sk, force=F, interval=5.0)
    inner = (res.section_kind == 0)
    outside = osteon.SECTION_FLAGS["outside"]
    assert np.all(res.section_flags[inner] & outside)
    assert np.allclose(res.section_area[inner], osteon.section_properties(circle(4.0, 128))["area"])


def test_joint_sections_use_the_mean_direction():
    # two bones at 90 degrees sharing a joint
    sk = osteon.Skeleton([[0, 0, 0], [40, 0, 0]], [[40, 0, 0], [40, 40, 0]], [-1, 0])
    v, f = merge(cylinder_along([0, 0, 0], [40, 0, 0], 4.0), cylinder_along([40, 0, 0], [40, 40, 0], 4.0))
    res = osteon.analyze(v, f, sk, interval=5.0)
    joint = np.flatnonzero(res.section_kind == 1)
    assert len(joint) == 1
    n = res.section_normal[joint[0]]
    assert np.allclose(np.abs(n), [np.sqrt(0.5), np.sqrt(0.5), 0])
    assert res.section_bone[joint[0]] == 1  # owned by the bone that leaves the joint


def test_weights_dense_sparse_and_nearest_agree():
    from scipy import sparse

    v, f, sk, part = branching()
    dense = np.zeros((len(v), 3))
    dense[np.arange(len(v)), part] = 1.0
    a = osteon.analyze(v, f, sk, dense)
    b = osteon.analyze(v, f, sk, sparse.csr_matrix(dense))
    c = osteon.analyze(v, f, sk, sparse.coo_array(dense))
    wide = sparse.csr_matrix(dense)
    wide.indices = wide.indices.astype(np.int64)  # 64-bit bone indices take the other path
    wide.indptr = wide.indptr.astype(np.int64)
    assert sparse.csr_matrix(dense).indices.dtype == np.int32
    d = osteon.analyze(v, f, sk, wide)
    for other in (b, c, d):
        assert np.array_equal(a.stress, other.stress, equal_nan=True)
        assert np.array_equal(a.vertex_stress, other.vertex_stress)


def test_threads_and_local_cuts_do_not_change_results():
    v, f, sk, _part = branching()
    ref = osteon.analyze(v, f, sk, threads=1, local_cuts=False)
    for threads, local in [(1, True), (2, True), (2, False)]:
        other = osteon.analyze(v, f, sk, threads=threads, local_cuts=local)
        assert np.allclose(ref.stress, other.stress, rtol=1e-12, equal_nan=True)
        if local:
            # Local cuts assemble the same loops from segments found in another order: the
            # section integrals agree to round-off, not bitwise.
            assert np.allclose(ref.vertex_stress, other.vertex_stress, rtol=1e-12, atol=0)
        else:
            assert np.array_equal(ref.vertex_stress, other.vertex_stress)
    local = osteon.analyze(v, f, sk, threads=1)
    assert np.array_equal(local.vertex_stress, osteon.analyze(v, f, sk, threads=2).vertex_stress)


def test_analyzer_reuse_matches_one_off_analysis():
    v, f, sk, _part = branching()
    an = osteon.Analyzer(f, len(v), sk, force=F)
    moved = v + [1.0, 2.0, 3.0]
    sk2 = osteon.Skeleton(sk.heads + [1, 2, 3], sk.tails + [1, 2, 3], sk.parents, sk.names)
    a = an.run(moved, sk2)
    b = osteon.analyze(moved, f, sk2, force=F)
    assert np.allclose(a.stress, b.stress, equal_nan=True)
    # translation does not change the physics
    c = an.run(v)
    assert np.allclose(a.stress, c.stress, rtol=1e-9, equal_nan=True)


def test_force_scales_stress_linearly():
    v, f = prism(circle(5.0, 64), 60.0)
    a = osteon.analyze(v, f, bar_skeleton(60.0), force=10.0)
    b = osteon.analyze(v, f, bar_skeleton(60.0), force=30.0)
    assert np.allclose(b.stress, 3 * a.stress, equal_nan=True)


@pytest.mark.parametrize(
    "bad,match",
    [
        ({"vertices": np.zeros((0, 3))}, "empty"),
        ({"vertices": np.full((3, 3), np.nan)}, "NaN"),
        ({"faces": np.array([[0, 1, 7]])}, "out of range"),
        ({"faces": np.array([[0, 1, -1]])}, "negative"),
        ({"faces": np.array([[0.0, 1.0, 2.0]])}, "integer"),
        ({"vertices": np.zeros((3, 2))}, r"shape \(N, 3\)"),
        ({"force": 0.0}, "force"),
        ({"allowable_stress": -1.0}, "allowable_stress"),
        ({"interval": 0.0}, "interval"),
        ({"root": "nope"}, "no bone named"),
    ],
)
def test_bad_input_raises_value_error(bad, match):
    args = {"vertices": np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]), "faces": np.array([[0, 1, 2]])}
    kwargs = {k: bad.pop(k) for k in list(bad) if k not in args}
    args.update(bad)
    sk = osteon.Skeleton([[0, 0, 0]], [[1, 0, 0]], [-1], ["bone"])
    with pytest.raises(ValueError, match=match):
        osteon.analyze(args["vertices"], args["faces"], sk, **kwargs)


@pytest.mark.parametrize(
    "heads,tails,parents,match",
    [
        ([[0, 0, 0]], [[0, 0, 0]], [-1], "zero length"),
        ([[0, 0, 0], [1, 0, 0]], [[1, 0, 0], [2, 0, 0]], [1, 0], "cycle"),
        ([[0, 0, 0]], [[1, 0, 0]], [3], "out of range"),
        ([[0, 0, 0]], [[1, 0, 0]], [0], "its own parent|cycle"),
        (np.zeros((0, 3)), np.zeros((0, 3)), [], "no bones"),
        ([[0, 0, np.inf]], [[1, 0, 0]], [-1], "NaN or infinity"),
    ],
)
def test_bad_skeleton_raises_value_error(heads, tails, parents, match):
    with pytest.raises(ValueError, match=match):
        osteon.Skeleton(heads, tails, parents)


def test_several_roots_are_joined_to_the_main_tree():
    v, f, sk, part = branching()
    weights = np.eye(3)[part]
    multi = osteon.Skeleton(sk.heads, sk.tails, [-1, -1, -1], sk.names)  # IK-like extra roots
    res = osteon.analyze(v, f, multi, weights, interval=5.0)
    ref = osteon.analyze(v, f, sk, weights, interval=5.0)
    # joined where their heads lie on the trunk: the same tree, the same moment arms
    assert res.held_bone == 0
    assert np.allclose(res.moment_arm, ref.moment_arm)


def test_analyzer_reuses_unchanged_sections_exactly(data_dir):
    """Live mode: after posing one limb, a re-run equals a fresh analysis of the posed mesh."""
    from rigged_models import load
    from scipy import sparse

    v, f, sk, w = load("elephant")
    an = osteon.Analyzer(f, len(v), sk, w)
    an.run(v)
    b = sk.num_bones - 1
    moving = np.asarray(sparse.csr_matrix(w).argmax(axis=1)).ravel() == b
    c, s = np.cos(0.3), np.sin(0.3)
    rot = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    posed = v.copy()
    posed[moving] = (v[moving] - sk.heads[b]) @ rot.T + sk.heads[b]
    tails = sk.tails.copy()
    tails[b] = (sk.tails[b] - sk.heads[b]) @ rot.T + sk.heads[b]
    posed_sk = osteon.Skeleton(sk.heads, tails, sk.parents, sk.names)
    again = an.run(posed, posed_sk)
    fresh = osteon.analyze(posed, f, posed_sk, w)
    assert np.array_equal(again.valid, fresh.valid)
    assert np.allclose(again.stress, fresh.stress, rtol=1e-12, equal_nan=True)
    assert np.allclose(again.vertex_stress, fresh.vertex_stress, rtol=1e-12)
    # and the pose really changed the result
    assert not np.allclose(again.stress, an.run(v, sk).stress, equal_nan=True)


def _shoelace_area(loop: np.ndarray, normal: np.ndarray) -> float:
    """Area (mm^2) of a closed planar 3D loop: half the cross-product sum, along the normal."""
    return 0.5 * abs(float(np.cross(loop, np.roll(loop, -1, axis=0)).sum(axis=0) @ normal))


def _outline_areas(res) -> np.ndarray:
    out = np.zeros(res.num_sections)
    for s, loops in enumerate(res.section_loops):
        if loops:
            n = res.section_normal[s]
            out[s] = _shoelace_area(loops[0], n) - sum(_shoelace_area(h, n) for h in loops[1:])
    return out


def test_section_outlines_enclose_the_section_area():
    # A tube (every section has a hole) on a bent two-bone skeleton (an oblique joint section).
    v, f = prism(circle(6.0, 48), 60.0, hole=circle(3.0, 48), stations=31)
    sk = osteon.Skeleton([[0, 0, 0], [30, 0, 0]], [[30, 0, 0], [60, 0.5, 0]], [-1, 0])
    assert osteon.analyze(v, f, sk, interval=4.0).section_loops is None  # only when asked
    res = osteon.analyze(v, f, sk, interval=4.0, keep_outlines=True)
    loops = res.section_loops
    assert len(loops) == res.num_sections
    valid = res.valid
    assert valid.sum() >= 14
    assert all(len(loops[s]) >= 1 for s in np.flatnonzero(valid))
    interior = np.flatnonzero(res.section_kind == 0)
    assert len(interior) == 14 and all(len(loops[s]) == 2 for s in interior)  # outer + hole
    assert all(len(loops[s]) == 0 for s in np.flatnonzero(~valid))
    np.testing.assert_allclose(_outline_areas(res)[valid], res.section_area[valid], rtol=1e-9)
    for s in np.flatnonzero(valid):  # on the section plane
        d = (np.concatenate(loops[s]) - res.section_point[s]) @ res.section_normal[s]
        np.testing.assert_allclose(d, 0.0, atol=1e-9)


def test_section_outlines_on_a_real_model(data_dir):
    from rigged_models import load

    v, f, sk, w = load("arm", height_mm=120.0)
    res = osteon.analyze(v, f, sk, w, interval=2.0, keep_outlines=True)
    plain = osteon.analyze(v, f, sk, w, interval=2.0)
    np.testing.assert_array_equal(res.stress, plain.stress)  # outlines change nothing else
    valid = res.valid
    np.testing.assert_allclose(_outline_areas(res)[valid], res.section_area[valid], rtol=1e-8)
    # Live mode: a re-run that reuses sections keeps their outlines.
    an = osteon.Analyzer(f, len(v), sk, w, interval=2.0, keep_outlines=True)
    an.run(v)
    again = an.run(v)
    np.testing.assert_array_equal(again.outline_points, res.outline_points)
