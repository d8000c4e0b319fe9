"""Robustness catalogue: every kind of bad or messy input and what the user gets (issue 6).

Every entry either raises ``ValueError`` whose message names the problem, or returns a result in
which the affected sections are flagged (``Analysis.section_flags``, names in
``osteon.SECTION_FLAGS``); never a crash, never a silent loss. Skipped sections (flag ``empty``
or ``degenerate``) have NaN modulus and stress and are neither weak nor culled.

============================================  =================================================
input                                         what the user gets
============================================  =================================================
**mesh**
NaN / ±inf vertex coordinate                  ValueError "vertices contain NaN or infinity (row i)"
face index >= V                               ValueError "face index out of range: i but there
                                              are V vertices"
negative face index                           ValueError "faces contain a negative vertex index"
float faces / string / object / bool arrays   ValueError "faces must be an integer array, got
                                              dtype ..." / "vertices must hold numbers ..."
vertices (V,2), (V,4), 1D; ragged lists       ValueError "vertices must have shape (N, 3), got ..."
quads (F,4) or 1D faces                       ValueError "faces must have shape (F, 3)
                                              (triangles), got ..."
empty mesh (no vertices / no faces)           ValueError "empty mesh: ..."
degenerate faces (repeated index,             ignored: the same stresses (a zero-area sliver
collinear corners)                             crossing a plane may add ``gap_closed``)
duplicate faces (same triangle, any winding)  dropped by the slicer: the same result, no flag
duplicate vertices (unwelded triangle soup)   sections flagged ``gap_closed``, same stresses as the
                                              welded mesh (any number of open chains); with
                                              ``gap_tolerance=0`` the sections are ``open`` +
                                              ``empty`` (NaN): weld first or keep a tolerance
open mesh (a slit in the wall)                sections through the slit ``open`` (+ ``empty``,
                                              NaN) when the gap exceeds the tolerance, else
                                              ``gap_closed``; the other sections unchanged
open tube (cylinder.obj), open / multi-piece  finite result; cuts that are closed loops are
real meshes (RigNet, wolf_clean)              analysed as solid, open cuts flagged
non-manifold edge (a fin on an edge)          sections cutting it flagged ``non_manifold``
several pieces                                sections use the piece around the bone; other pieces
                                              still count as load (moment arm), never as section
self-intersection (overlapping shells)        the bone point lies in two loops: nesting reads it as
                                              a hole, flag ``hollow``, the section is one shell
                                              (conservative: higher stress than the union)
**skeleton**
zero-length bone                              ValueError "bone 'b' has zero length"
NaN bone position                             ValueError "heads contain NaN or infinity"
bone length overflowing (|coord| ~ 1e160)     ValueError "bone 'b' is too long"
bone beside the mesh (point in no loop)       sections flagged ``outside``, nearest loop used
bone far outside the mesh                     sections flagged ``empty`` (nothing cut), NaN
parent index out of range (>= B or < -1)      ValueError "parent index p out of range [-1, B-1]"
parent cycle / own parent                     ValueError "parent cycle in skeleton through bone"
                                              / "is its own parent"
several root bones (IK, props)                no error: the main root (the root tree with most
                                              vertices) is held; every other root is joined to the
                                              nearest bone of the main tree (same result as
                                              parenting it there); ``root=`` may pick any bone
``root=`` unknown name / index / bool         ValueError "no bone named ..." / "bone index i out of
                                              range" / "root must be a bone index or name"
**weights**
wrong shape (dense or sparse)                 ValueError "weights must have shape (V, B) = ..."
negative (< -1e-6)                            ValueError "weights must not be negative (found w)"
tiny negative (>= -1e-6, solver round-off)    read as 0
NaN / inf                                     ValueError "weights contain NaN or infinity"
non-numeric                                   ValueError "weights must be numeric"
sparse bone (column) index >= B (SciPy does   ValueError "weights: bone (column) index i out of
not check it unless asked)                    range for B bones"
all-zero row                                  the vertex is bound to its nearest bone for the
                                              analysis; skinning/correction never move it
**settings**
force, allowable_stress, interval <= 0, NaN,  ValueError "force must be a positive finite number
inf or not a number                           (N), got ..." (likewise for the others)
interval so small a bone gets > 10^6 sections ValueError "interval too small"
gap_tolerance < 0 or NaN                      ValueError "gap_tolerance must be >= 0 mm"
max_scale < 1 / NaN, max_rounds < 0 or not    ValueError naming the parameter
an integer, target_ratio outside (0, 1]
scaling not "thin"/"uniform", flat_aspect     ValueError "scaling must be ..." / "flat_aspect
< 1, bone_x_axes wrong shape / NaN / along    must be >= 1" / "bone_x_axes must have shape"
the bone; skin() bone_scale_z without axes    / "... contain NaN" / "... across the bone" /
                                              "bone_scale_z needs bone_x_axes" (tested in
                                              test_correction.py)
threads < 0 or not an integer                 ValueError "threads must be an integer >= 0"
extreme scales (1e-6 mm and 1e6 mm models)    exact scaling: stress ∝ 1/L², moment ∝ L,
                                              modulus ∝ L³, area ∝ L², same flags
coordinates so large that J overflows (1e80)  sections flagged ``degenerate`` (NaN), never inf
**correction**
cannot converge (max_scale reached, max       ``converged=False`` and a ``reason`` naming the
rounds, blended joint weights)                stop rule and the sections that stay weak, within
                                              ``max_rounds`` rounds
**other entry points**
slice_section NaN origin / normal, zero       ValueError "origin and normal must be finite
normal                                        3-vectors, normal non-zero"
section_properties degenerate polygon         ``valid=False``, area 0 (no exception)
skin bone_scale wrong shape / <= 0            ValueError "bone_scale must ..."
Analyzer.run with another vertex/bone count   ValueError "... the analyzer was built for ..."
two threads calling analyze at once           the same results as sequential calls
============================================  =================================================
"""

from __future__ import annotations

import threading
from pathlib import Path

import numpy as np
import osteon
import pytest
from scipy import sparse
from shapes import cylinder_along, merge, revolve

SKIPPED = (osteon.SECTION_FLAGS["empty"] | osteon.SECTION_FLAGS["degenerate"]
           | osteon.SECTION_FLAGS["unreliable"])


def flag_set(res: osteon.Analysis) -> set[str]:
    """All flag names set on any section."""
    return {name for i in range(res.num_sections) for name in res.flag_names(i)}


def has_flag(res: osteon.Analysis, name: str) -> np.ndarray:
    return (res.section_flags & osteon.SECTION_FLAGS[name]) != 0


def assert_well_formed(res: osteon.Analysis, num_vertices: int) -> None:
    """Shapes, NaN stress <=> skipped flag, culled => not weak, finite per-vertex stress."""
    s = res.num_sections
    for name in ("section_bone", "section_area", "section_modulus", "moment_arm", "moment",
                 "culled", "weak", "section_flags"):
        assert getattr(res, name).shape == (s,), name
    assert res.section_center.shape == (s, 3) and res.section_normal.shape == (s, 3)
    skipped = (res.section_flags & SKIPPED) != 0
    np.testing.assert_array_equal(np.isnan(res.stress), skipped)
    np.testing.assert_array_equal(np.isnan(res.section_modulus), skipped)
    assert not (res.weak & res.culled).any()
    assert not (res.weak[skipped].any() or res.culled[skipped].any())
    assert (res.section_area >= 0).all()
    assert np.isfinite(res.moment_arm).all()
    assert res.vertex_stress.shape == (num_vertices,)
    assert np.isfinite(res.vertex_stress).all()
    assert np.isfinite(res.max_stress)


# --- fixtures -----------------------------------------------------------------------------------

def bar(radius: float = 4.0, length: float = 60.0, n: int = 32):
    """Closed round bar along +x, one ring of vertices per mm."""
    return revolve(np.linspace(0.0, length, int(length) + 1), np.full(int(length) + 1, radius), n)


def two_bones() -> osteon.Skeleton:
    return osteon.Skeleton([[1, 0, 0], [30, 0, 0]], [[30, 0, 0], [59, 0, 0]], [-1, 0],
                           names=["upper", "lower"])


def split_weights(v: np.ndarray) -> np.ndarray:
    w = np.zeros((len(v), 2))
    w[v[:, 0] < 30, 0] = 1.0
    w[v[:, 0] >= 30, 1] = 1.0
    return w


@pytest.fixture(scope="module")
def clean():
    v, f = bar()
    sk = two_bones()
    return v, f, sk, osteon.analyze(v, f, sk)


# --- mesh: values, indices, dtypes, shapes --------------------------------------------------------

@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_vertex(clean, bad):
    v, f, sk, _ = clean
    v = v.copy()
    v[7, 1] = bad
    with pytest.raises(ValueError, match=r"vertices contain NaN or infinity \(row 7\)"):
        osteon.analyze(v, f, sk)
    analyzer = osteon.Analyzer(f, len(v), sk)
    with pytest.raises(ValueError, match="vertices contain NaN or infinity"):
        analyzer.run(v)


def test_face_index_out_of_range(clean):
    v, f, sk, _ = clean
    f = f.copy()
    f[3, 2] = len(v)
    with pytest.raises(ValueError, match=f"face index out of range: {len(v)} but there are "
                                         f"{len(v)} vertices"):
        osteon.analyze(v, f, sk)
    f = f.astype(np.int64)
    f[3, 2] = 2**40  # would wrap around in int32
    with pytest.raises(ValueError, match="face index out of range"):
        osteon.analyze(v, f, sk)


def test_negative_face_index(clean):
    v, f, sk, _ = clean
    f = f.copy()
    f[0, 0] = -1
    with pytest.raises(ValueError, match=r"faces contain a negative vertex index \(-1\)"):
        osteon.analyze(v, f, sk)


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda v, f: (v, f.astype(float)), "faces must be an integer array, got dtype float64"),
        (lambda v, f: (v, f.astype(str)), "faces must be an integer array, got dtype <U"),
        (lambda v, f: (v, f.astype(bool)), "faces must be an integer array, got dtype bool"),
        (lambda v, f: (v.astype(str), f), "vertices must hold numbers, not dtype <U"),
        (lambda v, f: (v.astype(object), f), "vertices must hold numbers, not dtype object"),
        (lambda v, f: (v.astype(complex), f), "vertices must hold numbers, not dtype complex"),
    ],
)
def test_wrong_dtype(clean, make, message):
    v, f, sk, _ = clean
    v, f = make(v, f)
    with pytest.raises(ValueError, match=message):
        osteon.analyze(v, f, sk)


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda v, f: (v[:, :2], f), r"vertices must have shape \(N, 3\), got \(\d+, 2\)"),
        (lambda v, f: (np.hstack([v, v[:, :1]]), f), r"vertices must have shape \(N, 3\)"),
        (lambda v, f: (v.ravel(), f), r"vertices must have shape \(N, 3\), got \(\d+,\)"),
        (lambda v, f: ([[0, 0, 0], [1, 0]], f), r"vertices must .*shape \(N, 3\)"),
        (lambda v, f: (v, np.hstack([f, f[:, :1]])),
         r"faces must have shape \(F, 3\) \(triangles\), got \(\d+, 4\)"),
        (lambda v, f: (v, f.ravel()), r"faces must have shape \(F, 3\)"),
    ],
)
def test_wrong_shape(clean, make, message):
    v, f, sk, _ = clean
    v, f = make(v, f)
    with pytest.raises(ValueError, match=message):
        osteon.analyze(v, f, sk)


def test_empty_mesh(clean):
    v, f, sk, _ = clean
    with pytest.raises(ValueError, match="empty mesh: vertices has no rows"):
        osteon.analyze(np.zeros((0, 3)), f, sk)
    with pytest.raises(ValueError, match="empty mesh: faces has no rows"):
        osteon.analyze(v, np.zeros((0, 3), dtype=int), sk)
    with pytest.raises(ValueError, match="empty mesh: no vertices"):
        osteon.Analyzer(f, 0, sk)
    with pytest.raises(ValueError, match="empty mesh"):
        osteon.correct(np.zeros((0, 3)), f, sk, None)


# --- mesh: messy geometry ----------------------------------------------------------------------

def test_degenerate_faces_are_ignored(clean):
    v, f, sk, ref = clean
    far = len(v) - 1
    extra = np.array([[0, 0, 1], [2, 2, 2], [5, 6, 5], [1, 2, 1]])
    # A zero-area sliver: three collinear vertices (two existing, one appended midway).
    v2 = np.vstack([v, (v[0] + v[far]) / 2])
    sliver = np.array([[0, far, len(v)]])
    res = osteon.analyze(v, np.vstack([f, extra]), sk)
    assert_well_formed(res, len(v))
    np.testing.assert_allclose(res.stress, ref.stress, rtol=1e-12)
    np.testing.assert_array_equal(res.section_flags, ref.section_flags)
    # The sliver spans the whole bar: every plane cuts it into a zero-length open piece, which
    # gap closing removes (flag gap_closed); the stresses are unchanged.
    res = osteon.analyze(v2, np.vstack([f, extra, sliver]), sk)
    assert_well_formed(res, len(v2))
    np.testing.assert_allclose(res.stress, ref.stress, rtol=1e-12)
    assert flag_set(res) <= {"gap_closed"}


def test_duplicate_faces_are_ignored(clean):
    """Exact duplicates (either winding) are dropped by the slicer: same result, no flag."""
    v, f, sk, _ = clean
    ref = osteon.analyze(v, f, sk, interval=0.5)
    for extra in (f[::7], f[::7][:, [0, 2, 1]], f[:1].repeat(3, axis=0)):
        res = osteon.analyze(v, np.vstack([f, extra]), sk, interval=0.5)
        assert_well_formed(res, len(v))
        np.testing.assert_allclose(res.stress, ref.stress, rtol=1e-9)
        np.testing.assert_array_equal(res.section_flags, ref.section_flags)


def test_duplicate_vertices_unwelded_soup(clean):
    v, f, sk, ref = clean
    soup_v = v[f].reshape(-1, 3)
    soup_f = np.arange(len(soup_v)).reshape(-1, 3)
    res = osteon.analyze(soup_v, soup_f, sk)
    assert_well_formed(res, len(soup_v))
    assert flag_set(res) == {"gap_closed"}
    np.testing.assert_allclose(res.stress, ref.stress, rtol=1e-9)
    # Without gap closing nothing links up: every section is flagged open and skipped.
    res0 = osteon.analyze(soup_v, soup_f, sk, gap_tolerance=0.0)
    assert_well_formed(res0, len(soup_v))
    assert (has_flag(res0, "open") & has_flag(res0, "empty")).all()


def test_unwelded_fine_mesh_matches_welded():
    """More than 256 open chains per cut (300 triangles around the bar) still close up."""
    v, f = bar(n=300)
    sk = two_bones()
    ref = osteon.analyze(v, f, sk)
    soup_v = v[f].reshape(-1, 3)
    res = osteon.analyze(soup_v, np.arange(len(soup_v)).reshape(-1, 3), sk)
    assert flag_set(res) == {"gap_closed"}
    np.testing.assert_allclose(res.stress, ref.stress, rtol=1e-9)


def slit(v, f, x0, x1, width_deg=30.0):
    """Faces with the triangles between x0 and x1 within +-width/2 of the +y direction removed."""
    c = v[f].mean(axis=1)
    angle = np.degrees(np.abs(np.arctan2(c[:, 2], c[:, 1])))
    cut = (c[:, 0] > x0) & (c[:, 0] < x1) & (angle < width_deg / 2) & (np.abs(c[:, 1]) > 1.0)
    return f[~cut], cut.sum()


def test_open_mesh_slit(clean):
    v, f, sk, ref = clean
    f_open, removed = slit(v, f, 10.0, 20.0)
    assert removed > 0
    res = osteon.analyze(v, f_open, sk)
    assert_well_formed(res, len(v))
    x = res.section_point[:, 0]
    inside = (x > 10) & (x < 20)
    # The gap (a 30 degree arc of a 4 mm bar, ~2 mm) exceeds the default tolerance (1 % of the
    # model size): those sections are skipped and say why.
    assert (has_flag(res, "open") & has_flag(res, "empty"))[inside].all()
    assert np.isnan(res.stress[inside]).all()
    outside = (x < 9) | (x > 21)
    np.testing.assert_allclose(res.stress[outside], ref.stress[outside], rtol=1e-12)
    assert (res.section_flags[outside] == 0).all()
    # A tolerance wider than the gap closes it (flag gap_closed) and keeps the sections.
    res_wide = osteon.analyze(v, f_open, sk, gap_tolerance=5.0)
    assert_well_formed(res_wide, len(v))
    assert has_flag(res_wide, "gap_closed")[inside].all()
    assert np.isfinite(res_wide.stress[inside]).all()
    assert (res_wide.stress[inside] >= ref.stress[inside] * 0.999).all()  # less material


def test_open_tube_cylinder_obj(data_dir):
    from osteon.io import load_model

    m = load_model(data_dir / "Hyperspectral-Inverse-Skinning" / "cylinder.obj")
    res = osteon.analyze(m.vertices, m.faces, m.skeleton, m.weights)
    assert_well_formed(res, len(m.vertices))
    # Open only at its ends: the cuts along it are closed loops, analysed as a solid bar.
    assert res.valid.mean() > 0.9
    assert res.max_stress > 0


RIGNET = ["1347", "15446", "17872", "2586", "8184", "8333"]


@pytest.mark.parametrize("model", RIGNET)
def test_open_multi_piece_rignet(data_dir, model):
    from osteon.io import load_model

    m = load_model(data_dir / "RigNet" / f"{model}_ori.obj")
    res = osteon.analyze(m.vertices, m.faces, m.skeleton, m.weights)
    assert_well_formed(res, len(m.vertices))
    assert res.valid.any()
    # Multi-root rigs (RigNet duplicates root joints) are held at one root and fully analysed.
    assert set(np.unique(res.section_bone)) == set(range(m.skeleton.num_bones))


def test_open_rignet_sections_are_flagged(data_dir):
    """Open real meshes: the open cuts are reported (flags), not dropped silently."""
    from osteon.io import load_model

    flagged = 0
    for model in RIGNET:
        m = load_model(data_dir / "RigNet" / f"{model}_ori.obj")
        res = osteon.analyze(m.vertices, m.faces, m.skeleton, m.weights, gap_tolerance=0.0)
        flagged += int(has_flag(res, "open").sum())
        # Every skipped section says why.
        assert (res.section_flags[~res.valid] & SKIPPED).all()
    assert flagged > 0


def test_wolf_clean_open_three_pieces(data_dir):
    from osteon.io import load_model

    d = data_dir / "Hyperspectral-Inverse-Skinning"
    m = load_model(d / "wolf_clean.obj", skeleton=d / "wolf.tgf", weights=d / "wolf.DMAT")
    res = osteon.analyze(m.vertices, m.faces, m.skeleton, m.weights)
    assert_well_formed(res, len(m.vertices))
    assert res.valid.mean() > 0.5


def test_non_manifold_fin(clean):
    v, f, sk, _ = clean
    # A fin sharing the edges of one ring band: every such edge gets a third triangle.
    band = np.flatnonzero(np.all(np.isin(v[f][:, :, 0], [40.0, 41.0]), axis=1))[:4]
    tip = len(v)
    v2 = np.vstack([v, [[40.5, 0.0, 12.0]]])
    fins = np.array([[a, b, tip] for a, b, _ in f[band]])
    res = osteon.analyze(v2, np.vstack([f, fins]), sk, interval=0.5)
    assert_well_formed(res, len(v2))
    hit = (res.section_point[:, 0] > 40) & (res.section_point[:, 0] < 41)
    assert hit.any()
    assert has_flag(res, "non_manifold")[hit].all()
    far = (res.section_point[:, 0] < 39) | (res.section_point[:, 0] > 42)
    assert not has_flag(res, "non_manifold")[far].any()


def test_several_pieces(clean):
    v, f, sk, ref = clean
    v2, f2 = merge((v, f), (v + [0, 20, 0], f))  # a second bar beside the first
    res = osteon.analyze(v2, f2, sk)
    assert_well_formed(res, len(v2))
    # Sections are the piece around the bone; the other piece is not part of any section.
    np.testing.assert_allclose(res.section_area, ref.section_area, rtol=1e-12)
    np.testing.assert_allclose(res.section_modulus, ref.section_modulus, rtol=1e-12)
    assert (res.section_flags == 0).all()
    # ... but it is bound to the nearest bone, so it loads the skeleton (longer moment arms).
    assert (res.moment_arm >= ref.moment_arm - 1e-9).all()


def test_self_intersecting_shells(clean):
    v, f, sk, ref = clean
    v2, f2 = merge((v, f), (v + [0, 3, 0], f))  # two bars overlapping by 5 of their 8 mm
    res = osteon.analyze(v2, f2, sk)
    assert_well_formed(res, len(v2))
    interior = res.section_kind == 0
    assert not has_flag(res, "hollow")[interior].any()
    # The section is the union of the shells, as a slicer prints it (issue 12): more than one
    # bar, less than two (exact union areas: tests/python/test_printed_sections.py).
    a, one = res.section_area[interior], ref.section_area[interior]
    assert (a > 1.02 * one).all() and (a < 2 * one).all()


# --- skeleton ------------------------------------------------------------------------------------

def test_zero_length_bone():
    with pytest.raises(ValueError, match="bone 'b' has zero length"):
        osteon.Skeleton([[0, 0, 0], [1, 1, 1]], [[1, 0, 0], [1, 1, 1]], [-1, 0], names=["a", "b"])


def test_non_finite_bone():
    with pytest.raises(ValueError, match=r"heads contain NaN or infinity \(row 1\)"):
        osteon.Skeleton([[0, 0, 0], [np.nan, 0, 0]], [[1, 0, 0], [2, 0, 0]], [-1, 0])
    with pytest.raises(ValueError, match="tails contain NaN or infinity"):
        osteon.Skeleton([[0, 0, 0]], [[np.inf, 0, 0]], [-1])


def test_overflowing_bone_length():
    with pytest.raises(ValueError, match="bone 'bone_0' is too long"):
        osteon.Skeleton([[0, 0, 0]], [[1e160, 1e160, 0]], [-1])


def test_bone_beside_mesh_is_flagged_outside(clean):
    v, f, _, _ = clean
    sk = osteon.Skeleton([[1, 6, 0]], [[59, 6, 0]], [-1])  # 2 mm beside a 4 mm bar
    res = osteon.analyze(v, f, sk)
    assert_well_formed(res, len(v))
    assert has_flag(res, "outside").all()
    assert res.valid.all()  # the nearest loop (the bar) is used


def test_bone_far_outside_mesh_is_flagged_empty(clean):
    v, f, sk, _ = clean
    sk2 = osteon.Skeleton(sk.heads, sk.tails, sk.parents).scaled(1.0)
    sk2 = osteon.Skeleton(np.vstack([sk.heads, [[0, 0, 100]]]),
                          np.vstack([sk.tails, [[0, 0, 130]]]), [-1, 0, 0])
    res = osteon.analyze(v, f, sk2)
    assert_well_formed(res, len(v))
    third = res.section_bone == 2
    assert third.any()
    assert has_flag(res, "empty")[third].all() and np.isnan(res.stress[third]).all()
    assert res.valid[~third].all()


@pytest.mark.parametrize("parents, message", [
    ([-1, 5], r"parent index 5 out of range \[-1, 1\]"),
    ([-1, -2], r"parent index -2 out of range \[-1, 1\]"),
    ([-1, 2**40], "out of range"),
    ([1, 0], "parent cycle in skeleton through bone"),
    ([-1, 1], "bone 'bone_1' is its own parent"),
    ([-1, 0.5], "parents must be integers"),
    ([[-1], [0]], "parents must be a 1D integer array"),
    ([-1], r"heads, tails and parents must have the same length \(2, 2, 1\)"),
])
def test_bad_parents(parents, message):
    with pytest.raises(ValueError, match=message):
        osteon.Skeleton([[0, 0, 0], [0, 0, 1]], [[0, 0, 1], [0, 0, 2]], parents)


def test_longer_parent_cycle():
    heads = np.array([[0, 0, k] for k in range(4)], float)
    with pytest.raises(ValueError, match="parent cycle"):
        osteon.Skeleton(heads, heads + [0, 0, 1], [-1, 3, 1, 2])


def test_no_bones():
    with pytest.raises(ValueError, match="skeleton has no bones"):
        osteon.Skeleton(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, dtype=int))


def test_several_roots_join_nearest_bone(clean):
    v, f, sk, _ = clean
    heads = np.vstack([sk.heads, [[45, 0, 0]]])
    tails = np.vstack([sk.tails, [[45, 0, 8]]])  # an IK/prop bone starting on 'lower'
    multi = osteon.Skeleton(heads, tails, [-1, 0, -1])
    assert multi.roots == [0, 2]
    res = osteon.analyze(v, f, multi)
    assert_well_formed(res, len(v))
    assert res.held_bone == 0  # the root whose tree carries most vertices
    # Documented: the extra root is joined to the nearest bone of the main tree.
    joined = osteon.analyze(v, f, osteon.Skeleton(heads, tails, [-1, 0, 1]))
    np.testing.assert_array_equal(res.section_bone, joined.section_bone)
    np.testing.assert_allclose(res.stress, joined.stress, rtol=1e-12, equal_nan=True)
    np.testing.assert_allclose(res.moment_arm, joined.moment_arm, rtol=1e-12)


def test_several_roots_main_root_has_most_vertices(clean):
    v, f, _, _ = clean
    # Bone 0 is a tiny root beside the mesh end; bones 1-2 (second root) carry the bar.
    sk = osteon.Skeleton([[-5, 0, 0], [1, 0, 0], [30, 0, 0]], [[-4, 0, 0], [30, 0, 0], [59, 0, 0]],
                         [-1, -1, 1])
    res = osteon.analyze(v, f, sk)
    assert_well_formed(res, len(v))
    assert res.held_bone == 1
    # root= may hold any bone, also one of another root tree.
    res0 = osteon.analyze(v, f, sk, root=0)
    assert res0.held_bone == 0
    assert_well_formed(res0, len(v))


@pytest.mark.parametrize("root, message", [
    ("nope", "no bone named 'nope'"),
    (7, r"bone index 7 out of range \[0, 1\]"),
    (-1, r"bone index -1 out of range \[0, 1\]"),
    (True, "root must be a bone index or name"),
    (1.5, "root must be a bone index or name"),
])
def test_bad_root(clean, root, message):
    v, f, sk, _ = clean
    with pytest.raises(ValueError, match=message):
        osteon.analyze(v, f, sk, root=root)


def test_root_by_name_and_numpy_index(clean):
    v, f, sk, _ = clean
    assert osteon.analyze(v, f, sk, root="lower").held_bone == 1
    assert osteon.analyze(v, f, sk, root=np.int64(1)).held_bone == 1


# --- weights -------------------------------------------------------------------------------------

@pytest.mark.parametrize("shape", [(10, 2), "V,3", "V,1", "V"])
def test_weights_wrong_shape(clean, shape):
    v, f, sk, _ = clean
    shape = {"V,3": (len(v), 3), "V,1": (len(v), 1), "V": (len(v),)}.get(shape, shape)
    w = np.ones(shape)
    with pytest.raises(ValueError, match=r"weights must have shape \(V, B\) = \(\d+, 2\)"):
        osteon.analyze(v, f, sk, w)
    if len(shape) == 2:
        with pytest.raises(ValueError, match=r"weights must have shape \(V, B\)"):
            osteon.analyze(v, f, sk, sparse.csr_matrix(w))


def test_weights_negative(clean):
    v, f, sk, _ = clean
    w = split_weights(v)
    w[5, 1] = -0.5
    with pytest.raises(ValueError, match=r"weights must not be negative \(found -0.5\)"):
        osteon.analyze(v, f, sk, w)
    with pytest.raises(ValueError, match=r"weights must not be negative \(found -0.5\)"):
        osteon.analyze(v, f, sk, sparse.csr_matrix(w))


def test_weights_round_off_negative_reads_as_zero(clean):
    v, f, sk, _ = clean
    w = split_weights(v)
    noisy = w.copy()
    noisy[noisy == 0] = -1e-9
    a = osteon.analyze(v, f, sk, noisy)
    b = osteon.analyze(v, f, sk, w)
    np.testing.assert_array_equal(a.stress, b.stress)
    np.testing.assert_array_equal(a.vertex_bone, b.vertex_bone)


@pytest.mark.parametrize("index_type", [np.int32, np.int64])
def test_sparse_weights_bone_index_out_of_range(clean, index_type):
    v, f, sk, _ = clean
    w = sparse.csr_matrix(split_weights(v))
    w.indices = w.indices.astype(index_type)
    w.indices[7] = 5  # SciPy does not check column indices unless asked to
    with pytest.raises(ValueError, match=r"weights: bone \(column\) index 5 out of range for 2"):
        osteon.analyze(v, f, sk, w)


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_weights_non_finite(clean, bad):
    v, f, sk, _ = clean
    w = split_weights(v)
    w[3, 0] = bad
    with pytest.raises(ValueError, match="weights contain NaN or infinity"):
        osteon.analyze(v, f, sk, w)
    with pytest.raises(ValueError, match="weights contain NaN or infinity"):
        osteon.analyze(v, f, sk, sparse.csr_matrix(w))


def test_weights_non_numeric(clean):
    v, f, sk, _ = clean
    with pytest.raises(ValueError, match="weights must be numeric"):
        osteon.analyze(v, f, sk, split_weights(v).astype(str))


def test_all_zero_weight_rows(clean):
    v, f, sk, ref = clean
    w = split_weights(v)
    zero = np.arange(0, len(v), 5)
    w[zero] = 0.0
    res = osteon.analyze(v, f, sk, w)
    assert_well_formed(res, len(v))
    # Unweighted vertices are bound to their nearest bone for the analysis ...
    np.testing.assert_array_equal(res.vertex_bone[zero], ref.vertex_bone[zero])
    # ... and never move when bones are scaled (skinning and correction).
    moved = osteon.skin(v, sk, w, [2.0, 2.0])
    np.testing.assert_array_equal(moved[zero], v[zero])
    assert not np.allclose(moved, v)
    fix = osteon.correct(v, f, sk, w, allowable_stress=2.0, max_rounds=5)
    np.testing.assert_array_equal(fix.vertices[zero], v[zero])
    everything_zero = np.zeros((len(v), 2))
    res0 = osteon.analyze(v, f, sk, everything_zero)
    np.testing.assert_array_equal(res0.vertex_bone, ref.vertex_bone)
    np.testing.assert_allclose(res0.stress, ref.stress, rtol=1e-12)


# --- settings ------------------------------------------------------------------------------------

@pytest.mark.parametrize("name, unit", [("force", "N"), ("allowable_stress", "MPa"),
                                        ("interval", "mm")])
@pytest.mark.parametrize("value", [0.0, -1.0, np.nan, np.inf, "abc", None])
def test_bad_settings(clean, name, unit, value):
    v, f, sk, _ = clean
    with pytest.raises(ValueError, match=f"{name} must be a (positive finite )?number "
                                         rf"\({unit}\)"):
        osteon.analyze(v, f, sk, **{name: value})
    with pytest.raises(ValueError, match=name):
        osteon.correct(v, f, sk, split_weights(v), **{name: value})


def test_interval_too_small(clean):
    v, f, sk, _ = clean
    # the global budget (max_sections, issue 36) refuses first, naming the interval
    with pytest.raises(ValueError, match=r"refused: .* sections .* at 1e-09 mm .* above the "
                       r"limit of 200 000 sections"):
        osteon.analyze(v, f, sk, interval=1e-9)
    # lifted, the engine's own per-bone limit still holds
    with pytest.raises(ValueError, match="interval too small"):
        osteon.analyze(v, f, sk, interval=1e-5, max_sections=2**31 - 1)


@pytest.mark.parametrize("value", [-1.0, np.nan])
def test_bad_gap_tolerance(clean, value):
    v, f, sk, _ = clean
    with pytest.raises(ValueError, match="gap_tolerance must be >= 0 mm"):
        osteon.analyze(v, f, sk, gap_tolerance=value)


@pytest.mark.parametrize("kwargs, message", [
    ({"max_scale": 0.5}, "max_scale must be a finite number >= 1"),
    ({"max_scale": np.nan}, "max_scale must be a finite number >= 1"),
    ({"max_rounds": -1}, "max_rounds must be an integer >= 0"),
    ({"max_rounds": 1.5}, "max_rounds must be an integer >= 0"),
    ({"max_rounds": 10**12}, "max_rounds must be an integer"),
    ({"target_ratio": 0.0}, r"target_ratio must be in \(0, 1\]"),
    ({"target_ratio": np.nan}, r"target_ratio must be in \(0, 1\]"),
    ({"target_ratio": 1.5}, r"target_ratio must be in \(0, 1\]"),
    ({"threads": -2}, "threads must be an integer >= 0"),
])
def test_bad_correction_settings(clean, kwargs, message):
    v, f, sk, _ = clean
    with pytest.raises(ValueError, match=message):
        osteon.correct(v, f, sk, split_weights(v), **kwargs)


@pytest.mark.parametrize("threads", [-1, 2.5, 10**12, "2"])
def test_bad_threads(clean, threads):
    v, f, sk, _ = clean
    with pytest.raises(ValueError, match="threads must be an integer >= 0"):
        osteon.analyze(v, f, sk, threads=threads)


def off_grid_bones() -> osteon.Skeleton:
    """Bones whose section planes miss the bar's vertex rings (see the regression below)."""
    return osteon.Skeleton([[1.37, 0, 0], [30.37, 0, 0]], [[30.37, 0, 0], [58.37, 0, 0]], [-1, 0])


@pytest.mark.parametrize("scale", [1e-6, 1e6])
def test_extreme_scales(clean, scale):
    """Geometric scaling by s: area s², modulus s³, moment arm s, moment s, stress 1/s²."""
    v, f, _, _ = clean
    sk = off_grid_bones()
    ref = osteon.analyze(v, f, sk, min_thickness=0)
    assert (ref.section_flags == 0).all()
    res = osteon.analyze(v * scale, f, sk.scaled(scale), interval=2.0 * scale, min_thickness=0)
    assert_well_formed(res, len(v))
    assert res.num_sections == ref.num_sections
    np.testing.assert_array_equal(res.section_flags, ref.section_flags)
    np.testing.assert_allclose(res.section_area, ref.section_area * scale**2, rtol=1e-9)
    np.testing.assert_allclose(res.section_modulus, ref.section_modulus * scale**3, rtol=1e-9)
    np.testing.assert_allclose(res.moment_arm, ref.moment_arm * scale, rtol=1e-9)
    np.testing.assert_allclose(res.stress, ref.stress / scale**2, rtol=1e-9)
    np.testing.assert_allclose(res.vertex_stress, ref.vertex_stress / scale**2, rtol=1e-9)
    np.testing.assert_array_equal(res.weak, res.stress > res.allowable_stress)


def test_extreme_scale_planes_through_vertices(clean):
    """Regression (found by fuzz_section): planes exactly through vertex rings at 1e-6 mm lost
    their cut when the face grid rounded a cell box below the plane."""
    v, f, sk, ref = clean  # bones on integers: planes every 2 mm through the 1 mm vertex rings
    s = 1e-6
    res = osteon.analyze(v * s, f, sk.scaled(s), interval=2.0 * s, min_thickness=0)
    np.testing.assert_array_equal(res.section_flags, ref.section_flags)
    np.testing.assert_allclose(res.stress, ref.stress / s**2, rtol=1e-9)


def test_overflowing_coordinates_are_flagged(clean):
    v, f, sk, _ = clean
    s = 1e80  # J ~ r^4 overflows to inf
    res = osteon.analyze(v * s, f, sk.scaled(s), interval=2.0 * s, min_thickness=0)
    assert_well_formed(res, len(v))
    assert has_flag(res, "degenerate").all()


# --- correction that cannot converge -------------------------------------------------------------

def test_correct_cannot_converge_max_scale(clean):
    v, f, sk, _ = clean
    fix = osteon.correct(v, f, sk, split_weights(v), allowable_stress=1.0, max_scale=1.0)
    assert not fix.converged
    assert "cannot be fixed by scaling" in fix.reason
    assert "already at max_scale" in fix.reason
    assert "stay weak" in fix.reason
    assert fix.num_rounds == 0
    assert fix.unfixed_sections and fix.after.weak[fix.unfixed_sections].all()


def test_correct_cannot_converge_max_rounds(clean):
    v, f, sk, _ = clean
    fix = osteon.correct(v, f, sk, split_weights(v), allowable_stress=5.0, max_rounds=1)
    assert not fix.converged
    assert fix.reason.startswith("max_rounds reached")
    assert fix.num_rounds == 1
    assert fix.after.weak.any()


def test_correct_blended_joint_weights_ends(clean):
    """Blended weights everywhere: scaling is capped; the loop ends within max_rounds."""
    v, f, sk, _ = clean
    w = np.full((len(v), 2), 0.5)
    fix = osteon.correct(v, f, sk, w, allowable_stress=0.5, max_scale=1.5, max_rounds=30)
    assert not fix.converged
    assert fix.num_rounds <= 30
    assert "stay weak" in fix.reason
    assert (fix.bone_scale <= 1.5 + 1e-12).all()
    assert np.isfinite(fix.vertices).all()


# --- other entry points --------------------------------------------------------------------------

@pytest.mark.parametrize("origin, normal", [
    ([np.nan, 0, 30], [1, 0, 0]),
    ([30, 0, 0], [np.inf, 0, 0]),
    ([30, 0, 0], [0, 0, 0]),
    ([30, 0], [1, 0, 0]),
])
def test_slice_section_bad_plane(clean, origin, normal):
    v, f, _, _ = clean
    with pytest.raises(ValueError, match="origin and normal must be finite 3-vectors"):
        osteon.slice_section(v, f, origin, normal)


@pytest.mark.parametrize("outer", [
    [[0, 0], [1, 0]],                  # two points
    [[0, 0], [1, 0], [2, 0]],          # collinear
    [[0, 0], [1, 1], [1, 0], [0, 1]],  # bow tie: signed areas cancel
    [[1, 1], [1, 1], [1, 1]],          # one point
])
def test_section_properties_degenerate(outer):
    p = osteon.section_properties(outer)
    assert p["valid"] is False
    assert p["area"] == 0.0


def test_section_properties_bad_input():
    with pytest.raises(ValueError, match=r"outer contain NaN or infinity \(row 1\)"):
        osteon.section_properties([[0, 0], [1, np.nan], [0, 1]])
    with pytest.raises(ValueError, match=r"outer must have shape \(N, 2\)"):
        osteon.section_properties([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    with pytest.raises(ValueError, match="hole contain NaN"):
        osteon.section_properties([[0, 0], [4, 0], [0, 4]], [[[1, 1], [np.inf, 1], [1, 2]]])


def test_skin_bad_scales(clean):
    v, _, sk, _ = clean
    w = split_weights(v)
    with pytest.raises(ValueError, match=r"bone_scale must have shape \(2,\)"):
        osteon.skin(v, sk, w, [1.0])
    with pytest.raises(ValueError, match="bone_scale must be positive and finite"):
        osteon.skin(v, sk, w, [1.0, -2.0])
    with pytest.raises(ValueError, match="skin\\(\\) needs weights"):
        osteon.skin(v, sk, None, [1.0, 1.0])


def test_analyzer_run_mismatch(clean):
    v, f, sk, _ = clean
    analyzer = osteon.Analyzer(f, len(v), sk)
    with pytest.raises(ValueError, match=f"vertices has {len(v) - 1} rows, the analyzer was "
                                         f"built for {len(v)}"):
        analyzer.run(v[:-1])
    three = osteon.Skeleton(np.vstack([sk.heads, [[0, 0, 0]]]),
                            np.vstack([sk.tails, [[0, 0, 1]]]), [-1, 0, 0])
    with pytest.raises(ValueError, match="skeleton has 3 bones, the analyzer was built for 2"):
        analyzer.run(v, three)
    with pytest.raises(ValueError, match="skeleton must be an osteon.Skeleton"):
        osteon.analyze(v, f, "not a skeleton")


# --- threads -------------------------------------------------------------------------------------

def test_two_threads_match_sequential():
    """Two threads analysing different inputs at once give the sequential results (the engine
    releases the GIL, so the calls really overlap)."""
    a_v, a_f = bar(radius=3.0, length=80.0, n=96)
    a_sk = osteon.Skeleton([[1, 0, 0], [40, 0, 0]], [[40, 0, 0], [79, 0, 0]], [-1, 0])
    b_v, b_f = merge(cylinder_along([0, 0, 0], [0, 0, 50], 5.0, n=64, stations=50),
                     cylinder_along([0, 0, 25], [30, 0, 25], 2.0, n=64, stations=30))
    b_sk = osteon.Skeleton([[0, 0, 1], [0, 0, 25]], [[0, 0, 49], [29, 0, 25]], [-1, 0])
    jobs = [(a_v, a_f, a_sk, {"interval": 0.5}), (b_v, b_f, b_sk, {"interval": 0.25})]
    expected = [osteon.analyze(v, f, sk, **kw) for v, f, sk, kw in jobs]
    def work(i, barrier, results, errors):
        try:
            v, f, sk, kw = jobs[i]
            barrier.wait()
            results[i] = osteon.analyze(v, f, sk, **kw)
        except Exception as exc:  # noqa: BLE001 - any error fails the test below
            errors.append(exc)

    for _ in range(3):
        results: list = [None, None]
        errors: list = []
        barrier = threading.Barrier(2)
        threads = [threading.Thread(target=work, args=(i, barrier, results, errors))
                   for i in range(2)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        assert not errors
        for got, want in zip(results, expected):
            for name in ("stress", "section_modulus", "moment_arm", "section_flags",
                         "vertex_stress", "culled", "weak"):
                np.testing.assert_array_equal(getattr(got, name), getattr(want, name), name)


def test_thread_pool_many_calls_match_sequential(clean):
    from concurrent.futures import ThreadPoolExecutor

    v, f, sk, _ = clean
    inputs = [(v * s, sk.scaled(s)) for s in (0.5, 1.0, 1.5, 2.0, 3.0, 4.0)]
    expected = [osteon.analyze(vv, f, ss, threads=1).stress for vv, ss in inputs]
    with ThreadPoolExecutor(max_workers=4) as pool:
        got = list(pool.map(lambda a: osteon.analyze(a[0], f, a[1]).stress, inputs))
    for g, e in zip(got, expected):
        np.testing.assert_array_equal(g, e)


def test_catalogue_documented():
    """docs/robustness.md carries the same catalogue as this module."""
    doc = Path(__file__).resolve().parents[2] / "docs" / "robustness.md"
    text = doc.read_text()
    for entry in ("duplicate faces", "several root bones", "extreme scales", "fuzz",
                  "sanitize.sh"):
        assert entry in text
