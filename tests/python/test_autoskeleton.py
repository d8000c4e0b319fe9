"""osteon.auto_skeleton on generated closed meshes (issue 17): capsule, T, torus, two pieces,
degenerate input, and a cantilever checked against F·d/W.

The meshes are small (under ~1 100 vertices, so no simplification happens and pygel3d's
deterministic local-separator skeleton takes a few seconds each); the assertions are the
closed forms of the shapes: a limb's bone ends END_RATIO x its radius inside its end (just past
a round end's centre), the T's junction sits at the bars' meeting point."""

import numpy as np
import osteon
import pytest
from osteon.autoskeleton import END_RATIO, LoosePiecesWarning, split_pieces
from scipy import sparse
from shapes import capsule_along, cylinder_along, merge, revolve, torus

pytest.importorskip("pygel3d")

F = 10.0


def capsule(length=80.0, radius=6.0, n=24, stations=20, cap=8):
    """Closed capsule along +x: cylinder x in [0, length], hemispherical caps; tips at -r, L+r."""
    a = np.linspace(np.pi / 2, 0, cap + 1)[:-1]
    xs0 = -radius * np.sin(a)
    r0 = radius * np.cos(a)
    xs = np.r_[xs0, np.linspace(0, length, stations), length - xs0[::-1]]
    rs = np.r_[r0, np.full(stations, radius), r0[::-1]]
    rs[0] = rs[-1] = radius * 0.05
    return revolve(xs, rs, n)


def voxel_mesh(occ, h, origin, smooth=3):
    """Closed quad-surface of a boolean voxel grid (triangulated, welded), lightly smoothed."""
    occ = np.pad(occ, 1)
    quads = []
    _nx, ny, nz = occ.shape
    idx = lambda i, j, k: (i * (ny + 1) + j) * (nz + 1) + k
    for ax in range(3):
        diff = np.diff(occ.astype(np.int8), axis=ax)
        for sign in (1, -1):
            cells = np.argwhere(diff == sign)
            i, j, k = cells.T
            if ax == 0:
                i = i + 1
                q = [idx(i, j, k), idx(i, j + 1, k), idx(i, j + 1, k + 1), idx(i, j, k + 1)]
            elif ax == 1:
                j = j + 1
                q = [idx(i, j, k), idx(i, j, k + 1), idx(i + 1, j, k + 1), idx(i + 1, j, k)]
            else:
                k = k + 1
                q = [idx(i, j, k), idx(i + 1, j, k), idx(i + 1, j + 1, k), idx(i, j + 1, k)]
            q = np.stack(q, 1)
            if sign == 1:  # empty -> full along +axis: face points -axis
                q = q[:, ::-1]
            quads.append(q)
    q = np.concatenate(quads)
    used, inv = np.unique(q, return_inverse=True)
    q = inv.reshape(q.shape)
    k = used % (nz + 1)
    j = (used // (nz + 1)) % (ny + 1)
    i = used // ((nz + 1) * (ny + 1))
    v = np.column_stack([i, j, k]).astype(float) * h + np.asarray(origin) - h
    f = np.concatenate([q[:, [0, 1, 2]], q[:, [0, 2, 3]]]).astype(np.int32)
    e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    a = sparse.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(len(v),) * 2).tocsr()
    a = sparse.diags(1 / np.asarray(a.sum(1)).ravel()) @ a
    for _ in range(smooth):
        v = 0.5 * v + 0.5 * (a @ v)
    return v, f


def t_shape(h=3.0):
    """A T: bar along x (x in [-40, 40], z in [30, 42]), stem down to z = -40; 12 mm thick."""
    xs = np.arange(-40, 40, h) + h / 2
    ys = np.arange(-6, 6, h) + h / 2
    zs = np.arange(-40, 42, h) + h / 2
    X, Y, Z = np.meshgrid(xs, ys, zs, indexing="ij")
    occ = ((Z >= 30) | (np.abs(X) <= 6)) & (np.abs(Y) <= 6)
    return voxel_mesh(occ, h, (xs[0] - h / 2, ys[0] - h / 2, zs[0] - h / 2))


def free_ends(sk):
    """Bone end points no other bone touches (limb tips; the root's head if it is an end)."""
    pts, degree = joints(sk)
    return pts[degree == 1]


def joints(sk, tol=1e-6):
    """(points, degree): every bone end point and how many bones meet there."""
    pts = np.concatenate([sk.heads, sk.tails])
    key = np.round(pts / max(tol, 1e-9)).astype(np.int64)
    uniq, inv, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    first = np.zeros(len(uniq), np.int64)
    first[inv.ravel()] = np.arange(len(pts))
    return pts[first], counts


def check_weights(w, nv, nb):
    assert sparse.issparse(w)
    assert w.shape == (nv, nb)
    np.testing.assert_allclose(np.asarray(w.sum(1)).ravel(), 1.0, atol=1e-9)
    assert np.diff(w.tocsr().indptr).max() <= 4
    assert w.min() >= 0


@pytest.mark.parametrize("root", ["centre", "base"])
def test_capsule_gets_one_chain_along_its_axis_reaching_both_ends(root):
    v, f = capsule()
    sk, w = osteon.auto_skeleton(v, f, root=root, up=(1, 0, 0))
    check_weights(w, len(v), sk.num_bones)
    d = (sk.tails - sk.heads) / sk.lengths[:, None]
    angle = np.degrees(np.arccos(np.clip(np.abs(d[:, 0]), 0, 1)))
    assert angle.max() < 5.0, angle
    # a chain: no joint where three bones meet
    _, degree = joints(sk)
    assert degree.max() <= 2
    ends = np.concatenate([sk.heads, sk.tails])
    assert np.abs(ends[:, 1:]).max() < 2.0  # on the axis (r = 6 mm)
    # The chain stops END_RATIO radii inside each tip (tips at -6 and 86 mm): just past the
    # centre of each hemispherical end, where the capsule's medial axis ends; no section is cut
    # inside the end caps, where they would shrink to slivers.
    inset = END_RATIO * 6.0
    assert ends[:, 0].min() == pytest.approx(-6 + inset, abs=1.0)
    assert ends[:, 0].max() == pytest.approx(86 - inset, abs=1.0)
    if root == "base":  # held at the end it stands on (the lowest along up = +x)
        assert sk.parents[0] == -1 and sk.heads[0, 0] < 5.0


def test_t_shape_gets_one_junction_and_three_branches():
    v, f = t_shape()
    sk, w = osteon.auto_skeleton(v, f)
    check_weights(w, len(v), sk.num_bones)
    tips = free_ends(sk)
    assert len(tips) == 3, tips
    # each branch ends END_RATIO half-thicknesses (6 mm) inside its flat end, on its axis
    inset = END_RATIO * 6.0
    for tip in ([-40 + inset, 0, 36], [40 - inset, 0, 36], [0, 0, -40 + inset]):
        assert np.linalg.norm(tips - tip, axis=1).min() < 2.5, (tip, tips)
    pts, degree = joints(sk)
    junctions = pts[degree >= 3]
    assert len(junctions) == 1, junctions
    # re-centred on the meeting point of the bars' axes: within a quarter of the 12 mm bar
    assert np.linalg.norm(junctions[0] - [0, 0, 36]) < 3.0


def test_branches_thinner_than_printable_get_no_bone():
    """The T's bars are 12 mm thick: with a minimum printable thickness of 20 mm every leaf
    branch is too thin to print and is pruned, all in the same round; the branch that holds the
    root stays (something must carry the model), so one chain is left: no junction, and at
    least one of the T's three ends has no bone reaching it. With 10 mm, all three stay."""
    v, f = t_shape()
    sk, w = osteon.auto_skeleton(v, f, min_thickness=20.0)
    check_weights(w, len(v), sk.num_bones)
    _, degree = joints(sk)
    assert degree.max() <= 2
    assert len(free_ends(sk)) == 2
    ends = np.concatenate([sk.heads, sk.tails])
    reached = [np.linalg.norm(ends - e, axis=1).min() < 10.0
               for e in ([-40, 0, 36], [40, 0, 36], [0, 0, -40])]
    assert sum(reached) < 3, reached
    sk10, _ = osteon.auto_skeleton(v, f, min_thickness=10.0)
    assert len(free_ends(sk10)) == 3


def test_torus_loop_is_cut_into_a_tree():
    R, r = 30.0, 8.0
    v, f = torus(R, r)
    sk, w = osteon.auto_skeleton(v, f)
    check_weights(w, len(v), sk.num_bones)
    assert sk.roots == [0]  # Skeleton() rejects cycles, so this is a tree with one root
    # bones follow the ring's centre line...
    mids = 0.5 * (sk.heads + sk.tails)
    assert np.abs(np.linalg.norm(mids[:, :2], axis=1) - R).max() < r
    # ...all the way round, cut once: two free ends, opposite the root along the ring
    tips = free_ends(sk)
    assert len(tips) == 2
    # (each half stops END_RATIO tube radii short of the cut, like a limb's end)
    assert np.linalg.norm(tips[0] - tips[1]) < (2 * END_RATIO + 1) * r
    assert np.linalg.norm(tips.mean(0) - sk.heads[0]) > 1.5 * R
    covered = np.linalg.norm(np.concatenate([sk.heads, sk.tails])[:, None, :2]
                             - (R * np.column_stack([np.cos(np.linspace(0, 6.28, 36)),
                                                     np.sin(np.linspace(0, 6.28, 36))]))[None],
                             axis=2).min(0)
    assert covered.max() < 20.0


def sphere(centre, r, n=16, m=8):
    """Closed UV sphere of radius r (mm) about centre."""
    t = np.linspace(0, np.pi, m + 1)
    radii = r * np.sin(t)
    radii[0] = radii[-1] = 0.05 * r
    v, f = revolve(-r * np.cos(t), radii, n)
    return v + np.asarray(centre, float), f


def creature():
    """A head (capsule along x, r = 10 mm, tip at x = 90) with two eyes poking out of its
    surface, a third eye wholly inside it, a beak overlapping its tip, and a loose prop 30 mm
    away: (parts (list of (v, f)), index of the loose part)."""
    head = capsule_along((0, 0, 0), (80, 0, 0), 10.0, n=16, cap_stations=5, stations=10)
    parts = [head, sphere((84, 4, 5), 3), sphere((84, -4, 5), 3), sphere((70, 0, 0), 2),
             capsule_along((86, 0, 0), (100, 0, 0), 3.0, n=8, cap_stations=3, stations=4),
             sphere((40, 40, 0), 5)]
    return parts, 5


def test_pieces_touching_the_body_join_it_and_loose_ones_are_reported():
    parts, loose = creature()
    v, f = merge(*parts)
    counts = np.cumsum([0] + [len(p[0]) for p in parts])
    p = split_pieces(v, f)
    assert len(p.joined) == 4 and len(p.loose) == 1  # 2 eyes + inner eye + beak; the prop
    assert set(p.labels[counts[loose] : counts[loose + 1]]) == set(p.loose)
    assert set(p.labels[: counts[1]]) == {p.main}
    with pytest.warns(LoosePiecesWarning, match="1 loose piece"):
        sk, w = osteon.auto_skeleton(v, f)
    check_weights(w, len(v), sk.num_bones)
    # the head is rigged as it would be alone: same bones; the eyes get none, the beak (r = 3
    # mm, 13 mm past the head's tip: longer than wide, a limb end modelled as a small piece,
    # ``autoskeleton.piece_tips``) one, hung from the head's bone and ending within 1.5 of its
    # radii of its tip (x = 103 mm)
    sk_head, w_head = osteon.auto_skeleton(*parts[0])
    nh = sk_head.num_bones
    assert sk.num_bones == nh + 1
    assert np.array_equal(sk.heads[:nh], sk_head.heads)
    assert np.array_equal(sk.tails[:nh], sk_head.tails)
    assert np.array_equal(sk.parents[:nh], sk_head.parents)
    assert np.linalg.norm(sk.tails[nh] - [103, 0, 0]) < 1.5 * 3.0
    assert sk.heads[nh][0] > 70 and sk.tails[sk.parents[nh]][0] > 70  # from the head's front
    assert (w[: counts[1], :nh] != w_head).nnz == 0
    beak = slice(counts[4], counts[5])
    assert (w[beak].argmax(1) == nh).mean() > 0.5  # most of the beak moves with its bone
    # the loose prop is bound whole to one bone (the one nearest it)
    prop = w[counts[loose] : counts[loose + 1]].toarray()
    assert np.all(prop.max(1) == 1.0) and len(set(prop.argmax(1))) == 1
    # an eye moves with the head next to it: its weights are the head's nearest vertex's
    eye = slice(counts[1], counts[2])
    nearest = np.linalg.norm(v[eye][:, None] - parts[0][0][None], axis=2).argmin(1)
    assert (w[eye][:, :nh] != w_head[nearest]).nnz == 0 and w[eye][:, nh].nnz == 0


def test_a_limb_modelled_apart_gets_bones_of_its_own():
    """Two capsules crossing (an X of two separate closed pieces, both as big): the second is
    joined to the first and gets its own bones, hung from the first's; each of the 4 ends has
    a bone ending END_RATIO radii inside it."""
    r = 6.0
    a = capsule_along((-40, 0, 0), (40, 0, 0), r, n=12, cap_stations=4, stations=12)
    b = capsule_along((0, -40, 0), (0, 40, 0), r, n=12, cap_stations=4, stations=12)
    v, f = merge(a, b)
    p = split_pieces(v, f)
    assert len(p.joined) == 1 and not p.loose
    sk, w = osteon.auto_skeleton(v, f)
    check_weights(w, len(v), sk.num_bones)
    assert len(sk.roots) == 1  # one tree
    ends = np.concatenate([sk.heads, sk.tails])
    for tip in ([-46, 0, 0], [46, 0, 0], [0, -46, 0], [0, 46, 0]):
        assert np.linalg.norm(ends - tip, axis=1).min() < (END_RATIO + 0.5) * r, tip


@pytest.mark.parametrize("name,joined,loose", [("8184", 2, 0), ("8333", 1, 0)])
def test_rignet_models_in_several_pieces_are_rigged_whole(name, joined, loose):
    """RigNet 8184 (3 pieces) and 8333 (2 pieces; tests/data/RigNet): pieces counted as the
    checked mesh has them (the smaller pieces touch the body), one tree, every vertex weighted;
    before, auto_skeleton refused them ("mesh is in 3 separate pieces")."""
    from osteon.autoskeleton.mesh import check_mesh
    from osteon.io import load_model
    from rigged_models import DATA

    obj = DATA / "RigNet" / f"{name}_ori.obj"
    m = load_model(obj, skeleton=obj.with_name(f"{name}_ori_rig.txt"), height_mm=120)
    v, f = np.asarray(m.vertices), np.asarray(m.faces)
    p = split_pieces(*check_mesh(v, f)[:2])
    assert (len(p.joined), len(p.loose)) == (joined, loose)
    sk, w = osteon.auto_skeleton(v, f)
    check_weights(w, len(v), sk.num_bones)
    assert len(sk.roots) == 1 and sk.num_bones >= 5


def test_a_tapering_toe_gets_a_tip_bone_to_its_point():
    """RigNet 8333's right foot (tests/data/RigNet, 120 mm tall) ends in a toe that tapers to a
    point on the ground: its limb radius near the tip is 1.8 mm (the bench's extremity measure,
    tests/python/extremities.py). The end bone stops where the sections fall under a tenth of the
    limb's median area, 5.6 mm from the toe's front vertex (3.1 radii); the tip bone goes on
    to where the toe is END_RATIO radii from its end and still as thick as printable, within
    1.5 radii of the point."""
    from osteon.io import load_model
    from rigged_models import DATA

    obj = DATA / "RigNet" / "8333_ori.obj"
    m = load_model(obj, skeleton=obj.with_name("8333_ori_rig.txt"), height_mm=120)
    v, f = np.asarray(m.vertices), np.asarray(m.faces)
    sk, _w = osteon.auto_skeleton(v, f)
    ground = np.flatnonzero((v[:, 1] < 2.0) & (v[:, 0] > 0))  # the right foot's sole
    toe = v[ground[np.argmax(v[ground, 2])]]  # its frontmost vertex: the toe's point
    ends = np.concatenate([sk.heads, sk.tails])
    assert np.linalg.norm(ends - toe, axis=1).min() < 1.5 * 1.8, toe


def test_a_thin_branch_the_simplified_mesh_lost_gets_a_bone():
    """RigNet 8184 (tests/data/RigNet, 120 mm tall) ends at the top in a thin point,
    1.1 mm in limb radius (the bench's extremity measure, tests/python/extremities.py), that the
    simplified copy does not keep: the chain through the head stopped 4.7 mm (4.2 radii) from
    its top vertex. The thin-branch step (``autoskeleton.thin``) finds it on the full mesh
    and gives it a bone ending within 1.5 radii of it."""
    from osteon.io import load_model
    from rigged_models import DATA

    obj = DATA / "RigNet" / "8184_ori.obj"
    m = load_model(obj, skeleton=obj.with_name("8184_ori_rig.txt"), height_mm=120)
    v, f = np.asarray(m.vertices), np.asarray(m.faces)
    sk, w = osteon.auto_skeleton(v, f)
    check_weights(w, len(v), sk.num_bones)
    top = v[np.argmax(v[:, 1])]
    ends = np.concatenate([sk.heads, sk.tails])
    assert np.linalg.norm(ends - top, axis=1).min() < 1.5 * 1.1, top


def rig_reaching(v, f, tips, within):
    """auto_skeleton of (v, f), checked: valid weights, one tree, and a bone end within
    ``within`` mm of each of ``tips``; returns the skeleton."""
    sk, w = osteon.auto_skeleton(v, f)
    check_weights(w, len(v), sk.num_bones)
    assert len(sk.roots) == 1
    ends = np.concatenate([sk.heads, sk.tails])
    for tip in tips:
        assert np.linalg.norm(ends - tip, axis=1).min() < within, tip
    return sk


def segment_distance(p, a, b):
    """Distance (mm) from points p (..., 3) to the segment a-b."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    d = b - a
    t = np.clip(((p - a) @ d) / (d @ d), 0.0, 1.0)
    return np.linalg.norm(p - (a + t[..., None] * d), axis=-1)


def hand(r=4.0, h=1.5):
    """A hand as one closed mesh: a palm (ellipsoid 80 x 90 x 28 mm) and five capsule fingers
    of radius r (4 mm: 0.05 of the hand's 157 mm length, 0.1 of the palm's width), the thumb
    at 40 degrees; voxelised at h mm. Returns (v, f, finger axes [(base, end)], r)."""
    fingers = [((-27, 30, 0), (-30, 85, 0)), ((-9, 35, 0), (-9, 100, 0)),
               ((9, 35, 0), (9, 105, 0)), ((27, 30, 0), (30, 92, 0)),
               ((-30, -15, 0), (-75, 25, 0))]
    xs, ys, zs = (np.arange(lo, hi, h) + h / 2 for lo, hi in ((-90, 50), (-55, 120), (-20, 20)))
    X, Y, Z = np.meshgrid(xs, ys, zs, indexing="ij")
    occ = (X / 40) ** 2 + (Y / 45) ** 2 + (Z / 14) ** 2 <= 1
    for a, b in fingers:
        occ |= segment_distance(np.stack([X, Y, Z], -1), a, b) <= r
    v, f = voxel_mesh(occ, h, (xs[0] - h / 2, ys[0] - h / 2, zs[0] - h / 2))
    return v, f, fingers, r


def test_every_finger_of_a_hand_gets_a_bone_reaching_its_tip():
    """Fingers 8 mm wide and 60-70 mm long are limbs: a bone runs along each (within a radius
    of its axis half-way out) and ends within 1.5 radii of its tip (END_RATIO = 1.25 radii
    inside a round end)."""
    v, f, fingers, r = hand()
    sk, w = osteon.auto_skeleton(v, f)
    check_weights(w, len(v), sk.num_bones)
    ends = np.concatenate([sk.heads, sk.tails])
    for a, b in fingers:
        a, b = np.asarray(a, float), np.asarray(b, float)
        tip = b + r * (b - a) / np.linalg.norm(b - a)
        assert np.linalg.norm(ends - tip, axis=1).min() < 1.5 * r, (tip, ends)
        middle = 0.5 * (a + b)
        along = min(segment_distance(middle, h, t) for h, t in zip(sk.heads, sk.tails))
        assert along < r, (middle, along)


@pytest.mark.parametrize(
    "vertices,faces,match",
    [
        (np.zeros((0, 3)), np.zeros((0, 3), int), "vertices"),
        (np.eye(3), [[0, 1, 2]], "vertices"),
        (np.r_[np.eye(3), [[0.5, 0.5, 0]]] * 10, [[0, 1, 2], [0, 2, 3], [1, 2, 3], [0, 1, 3]],
         "no volume"),
        (np.r_[np.eye(3), [[np.nan, 0, 0]]], [[0, 1, 2], [0, 2, 3], [1, 2, 3], [0, 1, 3]], "NaN"),
        (np.zeros((4, 3)), [[0, 1, 2], [0, 2, 3], [1, 2, 3], [0, 1, 3]], "size 0"),
        (np.eye(4)[:, :3], [[0, 1, 2], [0, 2, 9], [1, 2, 3], [0, 1, 3]], "out of range"),
    ],
)
def test_degenerate_input_raises_value_error(vertices, faces, match):
    with pytest.raises(ValueError, match=match):
        osteon.auto_skeleton(vertices, faces)


def test_bad_options_raise_value_error():
    v, f = capsule(stations=10)
    for kw, match in [({"min_thickness": -1}, "min_thickness")]:
        with pytest.raises(ValueError, match=match):
            osteon.auto_skeleton(v, f, **kw)
    for kw, match in [({"detail": "huge"}, "detail"), ({"root": "top"}, "root"),
                      ({"up": (0, 0, 0)}, "up"), ({"spur": -1}, "spur")]:
        with pytest.raises(ValueError, match=match):
            osteon.auto_skeleton(v, f, **kw)


def test_cantilever_on_the_auto_skeleton_matches_f_d_over_w():
    length, radius, n = 80.0, 6.0, 32
    v, f = capsule(length, radius, n=n)
    sk, w = osteon.auto_skeleton(v, f, root="base", up=(1, 0, 0))
    res = osteon.analyze(v, f, sk, w, force=F, allowable_stress=60.0, interval=2.0)
    x = res.section_center[:, 0]
    inner = (res.section_flags == 0) & (x > 0.2 * length) & (x < 0.8 * length)
    assert inner.sum() > 10
    # polygon of n = 32 sides inscribed in the circle: W = pi r^3/4 within 2 %
    w_exact = np.pi * radius**3 / 4
    d = (length + radius) - x[inner]  # farthest downstream point: the far tip
    np.testing.assert_allclose(res.stress[inner], F * d / w_exact, rtol=0.05)
    # the weakest section is next to the hold
    assert x[np.argmax(np.where(res.section_flags == 0, res.stress, 0))] < 0.25 * length


def test_cli_uses_auto_skeleton_without_a_skeleton_file_and_writes_tgf_dmat(tmp_path, capsys):
    from osteon.cli import main
    from osteon.io import read_dmat, read_tgf, write_mesh

    v, f = capsule(n=16, stations=12)
    mesh = tmp_path / "capsule.stl"  # STL: a triangle soup, welded inside auto_skeleton
    write_mesh(mesh, v, f)
    assert main(["analyze", str(mesh), "--height-mm", "92", "--json", str(tmp_path / "r.json")]) == 0
    err = capsys.readouterr().err
    assert "auto_skeleton" in err
    assert main(["analyze", str(mesh), "--skeleton", "auto", "-q"]) == 0
    assert main(["skeleton", str(mesh), "--out", str(tmp_path / "capsule.tgf"),
                 "--height-mm", "92"]) == 0
    joints, _, heads, tails, parents = read_tgf(tmp_path / "capsule.tgf")
    w = read_dmat(tmp_path / "capsule.dmat")
    assert w.shape[1] == len(parents) and np.allclose(w.sum(1), 1.0)
    # written in the file's units (the capsule spans x in [-6, 86] in the file and is printed
    # 92 mm long: the bones end END_RATIO radii inside its tips)
    ends = np.concatenate([heads, tails])[:, 0]
    assert ends.min() == pytest.approx(-6 + END_RATIO * 6, abs=1.5)
    assert joints[:, 0].max() == pytest.approx(86 - END_RATIO * 6, abs=1.5)
    assert main(["analyze", str(mesh), "--skeleton", str(tmp_path / "capsule.tgf"),
                 "--weights", str(tmp_path / "capsule.dmat"), "-q"]) == 0


def test_a_blob_gets_one_bone_through_it():
    v = np.array([[x, y, z] for x in (0, 10) for y in (0, 10) for z in (0, 10)], float)
    f = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1], [2, 3, 7],
                  [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    sk, w = osteon.auto_skeleton(v, f)
    assert sk.num_bones >= 1
    check_weights(w, len(v), sk.num_bones)
    ends = np.concatenate([sk.heads, sk.tails])
    assert np.all((ends > -1e-9) & (ends < 10 + 1e-9))  # inside the cube


def test_seed_gives_identical_results():
    """auto_skeleton(seed=0) twice on the same T: identical bones and weights (bit for bit)."""
    v, f = t_shape()
    a_sk, a_w = osteon.auto_skeleton(v, f, seed=0)
    b_sk, b_w = osteon.auto_skeleton(v, f, seed=0)
    assert a_sk.num_bones == b_sk.num_bones
    assert np.array_equal(a_sk.heads, b_sk.heads) and np.array_equal(a_sk.tails, b_sk.tails)
    assert np.array_equal(a_sk.parents, b_sk.parents)
    assert (a_w != b_w).nnz == 0
    with pytest.raises(ValueError, match="seed"):
        osteon.auto_skeleton(v, f, seed="x")


def test_coarsening_keeps_about_ten_vertices_round_a_limb():
    """Issue 35: before the skeleton, edges shorter than SPACING x the local limb radius are
    collapsed. ``local_radius`` on a capsule's cylinder is its radius R (closed form: the
    deepest step t whose point is >= 0.8 t inside satisfies 2R - t >= 0.8 t, t <= 1.11 R; the
    steps grow by 1.76); after coarsening a capsule tessellated with 48 vertices round, the
    mesh is still a closed surface (V - E + F = 2) with about 2π / SPACING vertices round it."""
    from osteon.autoskeleton import curve
    from pygel3d import graph, hmesh

    r = 6.0
    v, f = capsule(length=80.0, radius=r, n=48, stations=41, cap=8)
    m = hmesh.Manifold.from_triangles(v, f)
    surface = hmesh.MeshDistance(m)
    size = 80.0 + 2 * r
    ring = (v[:, 0] > 20) & (v[:, 0] < 60)           # the cylinder, away from the caps
    normals = v[ring] * [0.0, 1.0, 1.0] / r
    rad = curve.local_radius(v[ring], normals, surface, size)
    assert np.all(rad > r / 1.8) and np.all(rad <= 1.12 * r), (rad.min(), rad.max())
    n_before = len(m.positions())
    assert curve.coarsen_by_radius(m, surface, size) > 0
    pos = np.asarray(m.positions())
    n_faces = len(list(m.faces()))
    n_edges = len(curve.graph_edges(graph.from_mesh(m), len(pos)))
    assert len(pos) - n_edges + n_faces == 2                # still a closed surface
    assert len(pos) < 0.5 * n_before
    # vertices round the cylinder: those in a band one axial spacing wide, per band
    mid = pos[(pos[:, 0] > 20) & (pos[:, 0] < 60)]
    spacing = curve.SPACING * r
    round_ = len(mid) / (40.0 / spacing)
    assert 0.5 * 2 * np.pi / curve.SPACING < round_ < 2 * 2 * np.pi / curve.SPACING, round_


def open_tube(start, end, r, n, stations):
    """A low-poly tube of radius r from ``start`` (open there: no cap) to ``end`` (closed by a
    fan): a limb modelled apart as an open shell, as low-poly models often have them."""
    v, f = cylinder_along(start, end, r, n=n, stations=stations)
    c0 = len(v) - 2  # revolve's centre of the cap at `start`
    f = f[~(f == c0).any(1)]
    f = np.where(f > c0, f - 1, f)
    return np.delete(v, c0, axis=0), f.astype(np.int32)


def test_low_poly_limbs_modelled_as_open_tubes_get_bones_to_their_tips():
    """A low-poly body (a 12-sided capsule) with three limbs glued on as open 6-sided tubes of
    two stations (the arms and legs of low-poly RigNet figures, issue 35): each limb gets
    bones of its own, ending within 1.5 radii of its tip (before: the open tubes got none and
    their tips were about 55 mm from any bone end)."""
    r = 4.0
    body = capsule_along((0, 0, 0), (60, 0, 0), 10.0, n=12, cap_stations=3, stations=4)
    tips = np.array([[10.0, 0, 55], [50.0, 0, 55], [30.0, 0, -50]])
    limbs = [open_tube((x, 0, 0), (x, 0, z), r, n=6, stations=2) for x, _, z in tips]
    v, f = merge(body, *limbs)
    p = split_pieces(v, f)
    assert len(p.joined) == 3 and not p.loose and not p.closed[p.joined].any()
    rig_reaching(v, f, tips, 1.5 * r)


def low_poly_cross(arm=40.0, half=4.0):
    """A plus sign in the xz plane, 2 x ``half`` thick and wide, arms reaching ±(half + arm):
    24 vertices, 44 triangles (each arm a box of 4 long edges, no vertex along it)."""
    a, b = half, half + arm
    xz = np.array([(a, -a), (b, -a), (b, a), (a, a), (a, b), (-a, b), (-a, a), (-b, a), (-b, -a),
                   (-a, -a), (-a, -b), (a, -b)])  # the outline, counter-clockwise in (x, z)
    v = np.concatenate([np.column_stack([xz[:, 0], np.full(12, y), xz[:, 1]]) for y in (-a, a)])
    faces = []
    for q in [(0, 3, 6, 9), (0, 1, 2, 3), (3, 4, 5, 6), (6, 7, 8, 9), (9, 10, 11, 0)]:
        faces += [[12 + q[0], 12 + q[2], 12 + q[1]], [12 + q[0], 12 + q[3], 12 + q[2]],
                  [q[0], q[1], q[2]], [q[0], q[2], q[3]]]
    for i in range(12):
        j = (i + 1) % 12
        faces += [[i, 12 + j, j], [i, 12 + i, 12 + j]]
    f = np.array(faces, np.int32)
    vol = np.einsum("ij,ij->", v[f[:, 0]], np.cross(v[f[:, 1]], v[f[:, 2]]))
    return v, (f if vol > 0 else f[:, ::-1].copy())


@pytest.mark.parametrize("arm", [25.0, 60.0])
def test_a_low_poly_cross_gets_a_bone_to_every_arm_tip(arm):
    """A 44-triangle plus sign (arms 8 x 8 mm boxes with no vertex along them): the mesh is
    split before skeletonising, so every arm gets a branch whose bone ends within 1.5 arm radii
    of its tip (issue 35; before: one bone, ends 4-16 radii from the tips)."""
    v, f = low_poly_cross(arm)
    sk, w = osteon.auto_skeleton(v, f)
    check_weights(w, len(v), sk.num_bones)
    ends = np.concatenate([sk.heads, sk.tails])
    b = 4.0 + arm
    for tip in ([b, 0, 0], [-b, 0, 0], [0, 0, b], [0, 0, -b]):
        assert np.linalg.norm(ends - tip, axis=1).min() < 1.5 * 4.0, tip


def test_cap_holes_closes_a_tube_outward_and_declines_a_sheet():
    """An open tube with a face flipped is capped into a closed, consistently outward mesh whose
    volume is the hexagonal prism's (circumradius r: 3√3/2 r² x length; both ends are flat
    fans); a flat sheet encloses nothing and is declined."""
    from osteon.autoskeleton.pieces import cap_holes

    r, length = 4.0, 50.0
    v, f = open_tube((0, 0, 0), (0, 0, length), r, n=6, stations=2)
    f = f.copy()
    f[3] = f[3, ::-1]
    cv, cf = cap_holes(v, f)
    half = np.concatenate([cf[:, [0, 1]], cf[:, [1, 2]], cf[:, [2, 0]]])
    assert len(np.unique(half, axis=0)) == len(half)  # every edge once each way: closed, oriented
    assert np.array_equal(cv[: len(v)], v)
    volume = np.einsum("ij,ij->", cv[cf[:, 0]], np.cross(cv[cf[:, 1]], cv[cf[:, 2]])) / 6
    assert volume == pytest.approx(1.5 * np.sqrt(3) * r**2 * length, rel=1e-9)
    sheet = np.array([[0, 0, 0], [10, 0, 0], [10, 10, 0], [0, 10, 0]], float)
    assert cap_holes(sheet, np.array([[0, 1, 2], [0, 2, 3]], np.int32)) is None


def test_front_skeleton_of_a_cylinder_is_one_chain_on_its_axis():
    """The level-set skeleton of a closed cylinder (radius 5 mm, 60 mm long, 16 sides, 13
    stations) from the centre of one end cap: its bands are as wide as the longest edge, so
    every ring of the distance's level sets lies in one node: the nodes form one chain (no
    vertex of degree 3, no loop), every node away from the two caps lies on the axis (the
    centroid of a whole ring: within a few % of the radius), and they reach from one end to the
    other."""
    from osteon.autoskeleton.curve import front_skeleton

    r, length = 5.0, 60.0
    v, f = cylinder_along((0, 0, 0), (0, 0, length), r, n=16, stations=13)
    edges = np.unique(np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), 1),
                      axis=0)
    start = int(np.argmin(np.linalg.norm(v - [0, 0, 0], axis=1)))  # the cap's centre
    npos, kedges, node = front_skeleton(v, edges, start)
    assert node.shape == (len(v),) and node.min() == 0 and node.max() == len(npos) - 1
    degree = np.bincount(kedges.ravel(), minlength=len(npos))
    assert degree.max() <= 2 and len(kedges) == len(npos) - 1  # a chain
    side = (npos[:, 2] > 2 * r) & (npos[:, 2] < length - 2 * r)
    assert side.sum() >= 3
    assert np.linalg.norm(npos[side, :2], axis=1).max() < 0.05 * r
    assert npos[:, 2].min() < r and npos[:, 2].max() > length - r


def flat_limb_body():
    """A low-poly body (a 12-sided capsule along x, r = 10 mm) with a flat limb glued on as an
    open 4-sided tube of two stations, 50 mm long, 12 x 3 mm across (a rhombus: the flat arms
    of RigNet 2586, issue 35); its tip at (30, 0, 55)."""
    body = capsule_along((0, 0, 0), (60, 0, 0), 10.0, n=12, cap_stations=3, stations=4)
    tv, tf = open_tube((0, 0, 0), (0, 0, 50), 1.0, n=4, stations=2)
    return merge(body, (tv * [6.0, 1.5, 1.0] + [30, 0, 5], tf))


def test_a_flat_low_poly_limb_modelled_apart_gets_one_bone_to_its_tip():
    """The flat limb is split before skeletonising, then skeletonised by the distance's level
    sets from where it meets the body (``front_skeleton``): it gets one chain of bones with one
    end, within 1.5 half-thicknesses (1.5 mm) of its tip (before: local separators on the split
    limb gave 5 bones ending 24 mm short of the tip)."""
    v, f = flat_limb_body()
    sk, w = osteon.auto_skeleton(v, f)
    check_weights(w, len(v), sk.num_bones)
    ends = np.concatenate([sk.heads, sk.tails])
    assert np.linalg.norm(ends - [30, 0, 55], axis=1).min() < 1.5 * 1.5
    in_limb = np.flatnonzero((sk.heads[:, 2] > 12) | (sk.tails[:, 2] > 12))
    leaves = [b for b in in_limb if b not in sk.parents]
    assert len(leaves) == 1


def test_a_long_closed_limb_modelled_apart_gets_bones_but_a_beak_does_not():
    """A closed capsule arm (r = 3 mm, 60 mm long: 4 % of the body's volume, 0.45 of the
    model's size, 11 x longer than wide) crossing a body capsule (r = 10 mm, 80 mm) gets bones
    to its tip within 1.5 radii, as RigNet 1347's closed arms (before: under BIG_PIECE x the
    body's volume, no bones, its tip 5 radii from any bone end); the test creature's beak (0.18
    of its size) gets no chain of its own, only a tip bone
    (``test_pieces_touching_the_body_join_it_...``)."""
    body = capsule_along((0, 0, 0), (80, 0, 0), 10.0, n=16, cap_stations=5, stations=10)
    arm = capsule_along((40, 0, 0), (40, 0, -60), 3.0, n=8, cap_stations=3, stations=12)
    v, f = merge(body, arm)
    p = split_pieces(v, f)
    assert len(p.joined) == 1 and p.closed[p.joined[0]]
    assert p.volume[p.joined[0]] < 0.1 * p.volume[p.main]
    sk, w = osteon.auto_skeleton(v, f)
    check_weights(w, len(v), sk.num_bones)
    assert len(sk.roots) == 1
    ends = np.concatenate([sk.heads, sk.tails])
    assert np.linalg.norm(ends - [40, 0, -63], axis=1).min() < 1.5 * 3.0
    from osteon.autoskeleton.assemble import CLOSED_LIMB_SIZE, elongated

    assert p.size[p.joined[0]] >= CLOSED_LIMB_SIZE * np.ptp(v, axis=0).max()
    assert elongated(arm[0]) and not elongated(sphere((0, 0, 0), 5)[0])


def box(lo, hi):
    """A closed box from corner ``lo`` to ``hi`` (mm): 8 vertices, 12 outward triangles."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    v = np.array([[x, y, z] for z in (z0, z1) for y in (y0, y1) for x in (x0, x1)], float)
    f = np.array([[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4],
                  [2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]], np.int32)
    return v, f


def test_two_limbs_sharing_an_edge_each_get_a_bone_to_their_tip():
    """Two closed 4 x 4 x 50 mm boxes sharing one long edge (that edge is in 4 faces: one
    piece that is neither closed nor a set of simple holes, as RigNet 8210's two missing limbs)
    glued into a body capsule: the piece is split at that edge into its two boxes
    (``manifold_parts``), each a long closed limb, and each gets a bone ending within 1.5
    half-widths (3 mm) of its tip (before: no bones, tips 50 mm from any bone end)."""
    body = capsule_along((0, 0, 0), (60, 0, 0), 10.0, n=12, cap_stations=3, stations=4)
    a, b = box((26, -4, 5), (30, 0, 55)), box((30, 0, 5), (34, 4, 55))
    v, f = merge(body, a, b)
    p = split_pieces(*osteon.autoskeleton.mesh.check_mesh(v, f)[:2])
    assert len(p.joined) == 1 and not p.closed[p.joined[0]]  # one piece: the boxes share an edge
    rig_reaching(v, f, ([28, -2, 55], [32, 2, 55]), 1.5 * 2.0)
    from osteon.autoskeleton.assemble import manifold_parts

    both = np.concatenate([a[1], b[1] + 8])
    both = np.where(both == 8 + 1, 3, np.where(both == 8 + 4 + 1, 7, both))  # shared corners
    assert sorted(len(x) for x in manifold_parts(both)) == [12, 12]


def test_open_limbs_plugged_into_an_open_body_join_it_and_get_bones():
    """A low-poly body modelled as an open shell (a 12-sided tube, r = 14 mm, open at the
    bottom) with two legs modelled as open 6-sided tubes (r = 4 mm) whose open tops reach
    12 mm up into it, 6 mm from its wall (RigNet 9477, issue 35): no leg vertex is near the
    body's surface, but the tops lie inside the body once its hole is capped, so the legs join
    it and each gets a bone ending within 1.5 radii of its foot (before: loose pieces, no
    bones, feet 60 mm from any bone end)."""
    r = 4.0
    body = open_tube((0, 0, 0), (0, 0, 70), 14.0, n=12, stations=4)
    feet = np.array([[-5.0, 0, -50], [5.0, 0, -50]])
    legs = [open_tube((x, 0, 12), (x, 0, z), r, n=6, stations=2) for x, _, z in feet]
    v, f = merge(body, *legs)
    p = split_pieces(v, f)
    assert len(p.joined) == 2 and not p.loose
    rig_reaching(v, f, feet, 1.5 * r)


def test_radius_inputs_from_the_triangles_in_bulk_match_pygel3d_and_the_shape():
    """Issue 35: the radius measuring reads the simplified mesh's triangles in one call
    (``curve.mesh_triangles``) and computes GEL's angle-weighted vertex normals in NumPy
    (``curve.vertex_normals``) instead of several pygel3d calls per face and vertex. On a
    capsule simplified by pygel3d (irregular triangles), the triangles are pygel3d's own face
    by face, the normals GEL's to rounding, and on the cylinder they point straight out from
    the axis (closed form: (0, y, z) / r)."""
    from osteon.autoskeleton import curve
    from pygel3d import hmesh

    r = 6.0
    v, f = capsule(length=80.0, radius=r, n=32, stations=30, cap=8)
    m = hmesh.Manifold.from_triangles(v, f)
    hmesh.quadric_simplify(m, 0.5)
    m.cleanup()
    pos = np.array(m.positions())
    tri = curve.mesh_triangles(m)
    assert tri.tolist() == [list(m.circulate_face(int(i), "v")) for i in m.faces()]
    normals = curve.vertex_normals(pos, tri)
    gel = np.array([m.vertex_normal(i) for i in range(len(pos))]).reshape(-1, 3)
    assert np.abs(normals - gel).max() < 1e-12
    mid = (pos[:, 0] > 10) & (pos[:, 0] < 70)
    radial = pos[mid] * [0.0, 1.0, 1.0]
    radial /= np.linalg.norm(radial, axis=1, keepdims=True)
    assert np.einsum("ij,ij->i", normals[mid], radial).min() > 0.95


def test_graph_edges_and_weld_read_in_bulk_match_the_slow_reading():
    """Issue 35 (Make skeleton under 2 s): the edges of pygel3d graphs are read from GEL's graph
    writer in one call (``curve.graph_edges``) and the weld's distinct rows from one lexsort
    (``mesh.unique_rows``). On a capsule's mesh graph and on its curve skeleton the edges are
    pygel3d's own, node by node, in the same order (the order in which edges are collapsed
    decides the bones); the weld gives np.unique's rows, first occurrences and inverse."""
    from osteon.autoskeleton import curve, mesh
    from pygel3d import graph, hmesh

    v, f = capsule(length=60.0, radius=5.0, n=16, stations=12, cap=4)
    m = hmesh.Manifold.from_triangles(v, f)
    g = graph.from_mesh(m)
    skel, _map = graph.LS_skeleton_and_map(g, sampling=False)
    for gr in (g, skel):
        n = len(gr.positions())
        slow = [(i, j) for i in gr.nodes() for j in gr.neighbors(i) if i < j]
        assert curve.graph_edges(gr, n).tolist() == [list(e) for e in slow]
    assert len(curve.graph_edges(g, len(v))) == 3 * len(f) // 2  # a closed mesh: E = 3F/2
    key = np.random.default_rng(1).integers(-3, 3, (500, 3))
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    got_first, got_inverse = mesh.unique_rows(key)
    assert got_first.tolist() == first.tolist()
    assert got_inverse.tolist() == inverse.ravel().tolist()


def test_the_bench_extremity_measure_finds_the_five_fingertips_of_a_hand():
    """Issue 35's rig-free measure (``tests/python/extremities.py``: maxima of the geodesic distance
    inside the voxelised solid from the body's centre of mass that stick out more than their
    width) on the test hand: exactly five extremities, one at each fingertip (the capsule's
    end, r beyond its axis' end) to within two voxels, each with the finger's radius r (4 mm)
    to within a voxel; the palm's far end (an ellipsoid: it sticks out less than its width) is
    none."""

    from extremities import extremities
    from osteon.autoskeleton.mesh import check_mesh

    v, f, fingers, r = hand()
    wv, wf, _ = check_mesh(v, f)
    ex = extremities(wv, wf, split_pieces(wv, wf))
    assert len(ex.tips) == 5
    for a, b in fingers:
        a, b = np.asarray(a, float), np.asarray(b, float)
        tip = b + r * (b - a) / np.linalg.norm(b - a)
        k = int(np.argmin(np.linalg.norm(ex.tips - tip, axis=1)))
        assert np.linalg.norm(ex.tips[k] - tip) < 2 * np.sqrt(3) * ex.h, (tip, ex.tips[k])
        assert abs(ex.radius[k] - r) < ex.h * np.sqrt(3), ex.radius[k]
    # the issue's definition (step 5': longer than its width across): the same five tips;
    # its radius (half the width across near the tip) is the finger's to within a voxel
    # and a half (the level sets cut the round end obliquely)
    iex = ex.issue
    assert len(iex.tips) == 5
    assert np.abs(iex.tips[:, None] - ex.tips[None]).sum(2).min(1).max() == 0.0
    assert (np.abs(iex.radius - r) < 1.5 * ex.h).all(), iex.radius


@pytest.mark.parametrize("a", [0.6, 0.8])
def test_the_bench_measures_a_thin_fingers_tip_and_radius_on_the_mesh(a):
    """Step 6 of ``tests/python/extremities.py``: a capsule finger of radius a = 0.6 / 0.8 mm
    (one voxel of the 0.76 mm grid: the voxel depth reads 0.76 mm for either), 10 mm out of
    a 120 mm body, is found as an extremity under both definitions; its tip is measured on
    the mesh (the cap's pole vertex, where a voxel centre lies up to ~h inside or short of
    it) and its radius from the mesh's distance field on a grid of h/6, not from voxel
    centres. Tolerances: the tip is a vertex of the cap's top (the finger's farthest point:
    ``capsule_along`` ends in a flat 64-gon of radius a sin(pi/24) = 0.08-0.10 mm, all of it
    equally far along the finger), the radius within sqrt(3)/2 h/6 = 0.11 mm (the grid's
    largest miss of the deepest point, of a 1-Lipschitz distance field) plus the capsule's
    64-gon chord error (0.1 %)."""

    from extremities import FINE, extremities
    from osteon.autoskeleton.mesh import check_mesh

    body = capsule_along((-48, 0, 0), (48, 0, 0), 12.0, n=32, cap_stations=8, stations=12)
    base, end = np.array([0.0, 0.0, 8.0]), np.array([0.0, 0.0, 22.0])
    finger = capsule_along(base, end, a, n=64, cap_stations=12, stations=24)
    v, f = merge(body, finger)
    wv, wf, _ = check_mesh(v, f)
    p = split_pieces(wv, wf)
    assert len(p.joined) == 1 and not p.loose
    ex = extremities(wv, wf, p)
    tip = end + np.array([0.0, 0.0, a])
    top = float(wv[:, 2].max())  # the cap's flat top, a sin(pi/24) round the axis
    tol_r = np.sqrt(3) / 2 * ex.h / FINE + 0.002 * a
    for e in (ex, ex.issue):
        k = int(np.argmin(np.linalg.norm(e.tips - tip, axis=1)))
        assert abs(e.tips[k, 2] - top) < 1e-9, (e.tips[k], top)
        assert np.linalg.norm(e.tips[k, :2]) <= a * np.sin(np.pi / 24) + 1e-9, e.tips[k]
        assert abs(e.radius[k] - a) < tol_r, (e.radius[k], a)
        # the voxel measure it replaces: a voxel centre short of the tip, a radius of one
        # voxel that does not tell 0.6 from 0.8 mm
        assert top - e.tips_voxel[k, 2] > 0.2, e.tips_voxel[k]
        assert abs(e.radius_voxel[k] - ex.h) < 1e-9, (e.radius_voxel[k], ex.h)
    # without step 6 the figures are the voxel ones
    ev = extremities(wv, wf, p, mesh_tips=False)
    assert np.array_equal(ev.tips, ex.tips_voxel) and np.array_equal(ev.radius, ex.radius_voxel)


def paddle_arms(h=1.0):
    """A body (ellipsoid 60 x 40 x 30 mm) with two arms (capsules of radius 4 mm, 35 mm long)
    each ending in a flat paddle 16 mm long, 24 mm wide and 4 mm thick; voxelised at h mm.
    Returns (v, f, the arms' (base, end) along x)."""
    xs, ys, zs = (np.arange(lo, hi, h) + h / 2 for lo, hi in ((-80, 80), (-30, 30), (-20, 20)))
    X, Y, Z = np.meshgrid(xs, ys, zs, indexing="ij")
    occ = (X / 30) ** 2 + (Y / 20) ** 2 + (Z / 15) ** 2 <= 1
    arms = []
    for s in (-1, 1):
        occ |= segment_distance(np.stack([X, Y, Z], -1), (s * 20, 0, 0), (s * 55, 0, 0)) <= 4
        occ |= (np.abs(X - s * 63) <= 8) & (np.abs(Y) <= 12) & (np.abs(Z) <= 2)
        arms.append(((s * 20.0, 0.0, 0.0), (s * 71.0, 0.0, 0.0)))
    v, f = voxel_mesh(occ, h, (xs[0] - h / 2, ys[0] - h / 2, zs[0] - h / 2))
    return v, f, arms


def test_the_issue_extremities_of_paddle_arms_are_the_arms_not_the_paddles_corners():
    """Issue 35 asks for bones on branches "longer than they are wide". A flat paddle (24 mm
    wide, 4 mm thick) at an arm's end has two far corners; step 5 of tests/python/extremities.py
    (width = twice the depth, 4 mm) counts both as extremities, the issue's definition
    (step 5': width across, 24 mm) only the arm: one extremity per arm, at a far corner of
    its paddle, with the limb radius half the paddle's breadth (12 mm, to within 2 voxels),
    so that a bone ending at the middle of the paddle's end reaches it."""

    from extremities import extremities
    from osteon.autoskeleton.mesh import check_mesh

    v, f, _arms = paddle_arms()
    wv, wf, _ = check_mesh(v, f)
    ex = extremities(wv, wf, split_pieces(wv, wf))
    assert len(ex.tips) == 3  # step 5: both corners of one paddle, one of the other
    iex = ex.issue
    assert len(iex.tips) == 2
    assert sorted(np.sign(iex.tips[:, 0]).tolist()) == [-1.0, 1.0]
    assert (np.abs(np.abs(iex.tips[:, 0]) - 71) < 2).all()  # the paddle's end
    assert (np.abs(np.abs(iex.tips[:, 1]) - 12) < 2).all()  # a corner of it
    assert (np.abs(iex.radius - 12) < 2 * ex.h).all(), iex.radius


def test_cli_skeleton_takes_the_minimum_printable_thickness_from_the_material(tmp_path, capsys):
    """``osteon skeleton --material``: the T's bars printed 0.56 mm thick (the 82 mm T at 3.8
    mm) are thinner than FDM prints (PLA: 0.8 mm, two 0.4 mm lines) and its leaf branches get
    no bone, as with ``min_thickness=0.8``; resin prints them (0.3 mm, osteon.materials) and
    all three ends keep their bones. The default is the FDM one."""
    from osteon.cli import main
    from osteon.io import read_tgf, write_mesh

    v, f = t_shape()
    mesh = tmp_path / "t.stl"
    write_mesh(mesh, v, f)
    ends = {}
    for material in (None, "PLA", "resin"):
        out = tmp_path / f"{material}.tgf"
        extra = [] if material is None else ["--material", material]
        assert main(["skeleton", str(mesh), "--out", str(out), "--height-mm", "3.8", "-q",
                     *extra]) == 0
        _, _, heads, tails, parents = read_tgf(out)
        ends[material] = len(free_ends(osteon.Skeleton(heads, tails, parents)))
    assert ends == {None: 2, "PLA": 2, "resin": 3}
    assert main(["skeleton", str(mesh), "--out", str(tmp_path / "x.tgf"), "--material",
                 "wood"]) != 0
    assert "unknown material 'wood'" in capsys.readouterr().err


def test_a_limb_end_modelled_as_a_small_piece_gets_a_bone_but_a_plate_does_not():
    """RigNet 1347's hands are small open boxes glued under its arms' ends, too small for
    bones of their own (``assemble``), so no bone reached them (4.4-8.1 limb radii). A 6 mm
    box sticking 10 mm out of a capsule's end is tested as a thin branch on the union of the
    pieces (``autoskeleton.piece_tips``) and gets a bone ending inside it within 1.5 of its
    half-widths of its end face; a fin 2.4 mm thick and 16 mm long standing 10 mm out of the
    capsule's side (a plate: its outer half as broad as it is long) gets none."""
    body = capsule_along((0, 0, 0), (80, 0, 0), 10.0, n=16, cap_stations=5, stations=10)
    v, f = merge(body, box((88, -3, -3), (100, 3, 3)), box((28, -1.2, 8), (44, 1.2, 20)))
    p = split_pieces(v, f)
    assert len(p.joined) == 2 and not p.loose
    sk, w = osteon.auto_skeleton(v, f)
    check_weights(w, len(v), sk.num_bones)
    assert len(sk.roots) == 1
    ends = np.concatenate([sk.heads, sk.tails])
    in_box = ends[(ends[:, 0] > 90) & (np.abs(ends[:, 1:]) < 3).all(1)]
    assert len(in_box) == 1 and 100 - in_box[0, 0] < 1.5 * 3.0
    assert ends[:, 2].max() < 10.0  # no bone into the fin


@pytest.mark.parametrize("radius,min_t,ok", [(0.35, 0.8, False), (0.35, 0.3, True),
                                             (0.45, 0.8, True)])
def test_the_bones_and_the_bench_share_one_printability_measure(radius, min_t, ok):
    """``autoskeleton.thickness``: a point prints when the local thickness there, twice its
    distance to the surface, is at least the material's minimum (FDM 0.8 mm, resin 0.3 mm).
    On a capsule of radius a that is 2a on its axis (closed form), so a 0.7 mm rod does not
    print at FDM and does in resin, a 0.9 mm one does at FDM; the bench's extremity flag
    (``extremities.tip_printable``: a printable point within 1.5 r of the tip, r = a) answers
    the same through the same function, and a point 0.1 a from the surface never prints."""

    from extremities import Extremities, tip_printable
    from osteon.autoskeleton.curve import _mesh_distance
    from osteon.autoskeleton.mesh import check_mesh
    from osteon.autoskeleton.thickness import printable

    v, f = capsule(length=20 * radius, radius=radius, n=48, stations=40, cap=16)
    wv, wf, _ = check_mesh(v, f)
    dist = _mesh_distance(wv, wf)
    axis = np.stack([np.linspace(0, 20 * radius, 11), np.zeros(11), np.zeros(11)], 1)
    inner = -np.asarray(dist.signed_distance(axis), float)
    assert np.allclose(inner, radius, rtol=0.01)
    assert (printable(inner, min_t) == ok).all()
    assert not printable(inner * 0.1, min_t).any()
    tip = np.array([[20 * radius + radius, 0.0, 0.0]])
    ex = Extremities(tip, np.array([radius]), np.ones(1), np.ones(1), radius / 10)
    assert tip_printable(wv, wf, split_pieces(wv, wf), ex, min_t).tolist() == [ok]


def test_an_arm_ending_in_a_paddle_gets_a_bone_to_the_paddle_s_end_not_its_corners():
    """Issue 35's bar on a flat end: the arms of ``paddle_arms`` (24 mm wide, 4 mm thick
    paddles) each get one chain whose bone ends at the middle of the paddle's end (x = ±71
    mm), within 1.5 of the issue's limb radii (half the paddle's breadth, 12 mm) of the
    paddle's far corners, where the bench's extremity tips lie; no bone goes to a corner (a
    corner is not a branch longer than it is wide: no bone ends within 4 mm of one)."""
    v, f, _arms = paddle_arms()
    sk, w = osteon.auto_skeleton(v, f)
    check_weights(w, len(v), sk.num_bones)
    ends = np.concatenate([sk.heads, sk.tails])
    for s in (-1, 1):
        end = np.array([s * 71.0, 0.0, 0.0])
        assert np.linalg.norm(ends - end, axis=1).min() < 1.25 * 2.0 + 1.0  # its middle
        for corner in ([s * 71.0, 12.0, 0.0], [s * 71.0, -12.0, 0.0]):
            dist = np.linalg.norm(ends - corner, axis=1).min()
            assert 4.0 < dist < 1.5 * 12.0, (corner, dist)
