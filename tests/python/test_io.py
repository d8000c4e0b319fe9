"""Readers on the real models in tests/data (counts, joint trees, weights) and round trips."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from conftest import DATA
from osteon.io import (
    RiggedModel,
    load_model,
    read_dmat,
    read_mesh,
    read_tgf,
    write_dmat,
    write_mesh,
    write_tgf,
)
from osteon.io.gltf import weld
from osteon.io.rignet import read_rignet_rig

LIBIGL = DATA / "libigl-tutorial-data"
HIS = DATA / "Hyperspectral-Inverse-Skinning"
RIGNET = DATA / "RigNet"
FOX = DATA / "glTF-Sample-Models" / "Fox.glb"

needs_data = pytest.mark.skipif(not DATA.is_dir(), reason=f"test data folder {DATA} absent")


def _count(path, prefix):
    with open(path) as f:
        return sum(1 for line in f if line.startswith(prefix))


def _tgf_counts(path):
    """Independent count of TGF joint and bone lines."""
    joints = bones = 0
    section = 0
    for line in Path(path).read_text().splitlines():
        if line.strip().startswith("#"):
            section += 1
            continue
        if line.strip():
            if section == 0:
                joints += 1
            elif section == 1:
                bones += 1
    return joints, bones


def _assert_rows_sum_to_one(w, allow_empty=False):
    s = np.asarray(w.sum(axis=1)).ravel()
    if allow_empty:
        s = s[s > 0]
    np.testing.assert_allclose(s, 1.0, atol=1e-9)
    assert w.data.min() >= 0


def _assert_tree(parents):
    B = len(parents)
    assert np.all((parents >= -1) & (parents < B))
    for b in range(B):  # no cycles
        k, steps = b, 0
        while k >= 0:
            k = parents[k]
            steps += 1
            assert steps <= B


@needs_data
@pytest.mark.parametrize(
    "mesh,tgf,dmat",
    [
        (LIBIGL / "arm.obj", LIBIGL / "arm.tgf", LIBIGL / "arm-weights.dmat"),
        (LIBIGL / "elephant.obj", LIBIGL / "elephant.tgf", LIBIGL / "elephant-weights.dmat"),
        (HIS / "cheburashka.obj", HIS / "cheburashka.tgf", HIS / "cheburashka.DMAT"),
        (HIS / "cow_clean.obj", HIS / "cow.tgf", HIS / "cow.DMAT"),
        (HIS / "wolf_clean.obj", HIS / "wolf.tgf", HIS / "wolf.DMAT"),
        (HIS / "cylinder.obj", HIS / "cylinder.tgf", HIS / "cylinder.DMAT"),
    ],
)
def test_tgf_dmat_models(mesh, tgf, dmat):
    m = load_model(mesh, skeleton=tgf, weights=dmat, height_mm=120)
    assert m.vertices.shape == (_count(mesh, "v "), 3)
    assert m.faces.shape == (_count(mesh, "f "), 3)
    nj, nb = _tgf_counts(tgf)
    assert m.n_bones == nb
    joints, E, _heads, _tails, _parents = read_tgf(tgf)
    assert len(joints) == nj
    np.testing.assert_allclose(m.heads / m.scale, joints[E[:, 0]], rtol=1e-12, atol=1e-12)
    # a bone's parent ends where it starts
    for b, p in enumerate(m.parents):
        if p >= 0:
            assert E[p, 1] == E[b, 0]
        else:
            assert not np.any(E[:, 1] == E[b, 0])
    _assert_tree(m.parents)
    assert m.weights.shape == (len(m.vertices), m.n_bones)
    _assert_rows_sum_to_one(m.weights)
    # DMAT values are kept (round-off negatives, e.g. -1e-12 in BBW files, become 0)
    raw = np.clip(read_dmat(dmat), 0.0, None)
    np.testing.assert_allclose(m.weights.toarray(), raw / raw.sum(1, keepdims=True), atol=1e-8)
    ext = m.vertices.max(0) - m.vertices.min(0)
    assert ext.max() == pytest.approx(120.0)


@needs_data
def test_sidecars_found():
    m = load_model(LIBIGL / "arm.obj")  # arm.tgf + arm-weights.dmat next to it
    assert m.n_bones == 4 and m.weights is not None
    m2 = load_model(RIGNET / "2982_ori.obj")  # 2982_ori_rig.txt next to it
    assert m2.n_bones > 0 and m2.weights is not None


def test_sidecars_in_any_case_and_a_folder_listed_once(tmp_path, monkeypatch):
    """A skeleton and weights whose names differ in letter case are found (the listing); a
    model whose sidecars are named exactly needs no listing; a flat folder of many models is
    listed once while it does not change (it was listed for every model: N² names)."""
    from pathlib import Path

    from batch_library import rigged_bar

    rigged_bar(tmp_path, "bar")
    (tmp_path / "bar.tgf").rename(tmp_path / "BAR.TGF")
    (tmp_path / "bar.dmat").rename(tmp_path / "Bar.DMAT")
    for i in range(3):
        rigged_bar(tmp_path, f"exact{i}")
    listed = []
    real = Path.iterdir
    monkeypatch.setattr(Path, "iterdir", lambda self: listed.append(self) or real(self))
    m = load_model(tmp_path / "bar.obj")
    assert m.n_bones == 2 and m.weights is not None
    for i in range(3):
        assert load_model(tmp_path / f"exact{i}.obj").weights is not None
    assert len(listed) <= 1


@needs_data
def test_binary_and_ascii_dmat_agree(tmp_path):
    raw = read_dmat(LIBIGL / "elephant-weights.dmat")  # this one is binary
    assert (LIBIGL / "elephant-weights.dmat").read_bytes()[:4] == b"0 0\n"
    assert raw.shape == (_count(LIBIGL / "elephant.obj", "v "), 24)
    for binary in (False, True):
        p = tmp_path / f"w{int(binary)}.dmat"
        write_dmat(p, raw, binary=binary)
        np.testing.assert_array_equal(read_dmat(p), raw)
    asc = read_dmat(LIBIGL / "arm-weights.dmat")
    header = (LIBIGL / "arm-weights.dmat").read_text().split("\n", 1)[0].split()
    assert asc.shape == (int(header[1]), int(header[0]))


@needs_data
def test_tgf_round_trip(tmp_path):
    joints, E, _heads, _tails, parents = read_tgf(LIBIGL / "elephant.tgf")
    p = tmp_path / "e.tgf"
    write_tgf(p, joints, E)
    j2, E2, _h2, _t2, p2 = read_tgf(p)
    np.testing.assert_array_equal(j2, joints)
    np.testing.assert_array_equal(E2, E)
    np.testing.assert_array_equal(p2, parents)


@needs_data
@pytest.mark.parametrize("ext", [".obj", ".off", ".ply", ".stl"])
def test_mesh_round_trip(tmp_path, ext):
    V, F = read_mesh(LIBIGL / "arm.obj")
    p = tmp_path / f"arm{ext}"
    write_mesh(p, V, F)
    V2, F2 = read_mesh(p)
    if ext == ".stl":  # STL stores triangles, not shared vertices
        np.testing.assert_allclose(V2[F2], V[F], rtol=1e-6, atol=1e-6)
    else:
        assert V2.shape == V.shape and F2.shape == F.shape
        np.testing.assert_allclose(V2, V, rtol=1e-6, atol=1e-7)
        np.testing.assert_array_equal(F2, F)


def _rignet_files():
    return sorted(RIGNET.glob("*_rig.txt")) if RIGNET.is_dir() else []


@needs_data
@pytest.mark.parametrize("rig", _rignet_files(), ids=lambda p: p.name)
def test_rignet_models(rig):
    mesh = rig.with_name(rig.name.replace("_rig.txt", ".obj"))
    m = load_model(mesh, skeleton=rig, height_mm=100)
    text = rig.read_text().splitlines()
    joints = {ln.split()[1]: ln.split()[2:5] for ln in text if ln.startswith("joints ")}
    hier = [ln.split()[1:3] for ln in text if ln.startswith("hier ")]
    skinned = {int(ln.split()[1]) for ln in text if ln.startswith("skin ")}
    assert m.vertices.shape == (_count(mesh, "v "), 3)
    assert m.faces.shape[0] == _count(mesh, "f ")
    # one bone per hier edge whose child is not a duplicated joint (an unweighted root bone
    # may be dropped)
    dup = re.compile(r"_dup_\d+$")
    edges = [(p, c) for p, c in hier if not dup.search(c)]
    assert len(edges) - 1 <= m.n_bones <= len(edges)
    # every bone tail is a joint of the file, at its scaled position
    pos = np.array([[float(x) for x in v] for v in joints.values()])
    for t in m.tails / m.scale:
        assert np.min(np.linalg.norm(pos - t, axis=1)) < 1e-9
    _assert_tree(m.parents)
    _assert_rows_sum_to_one(m.weights, allow_empty=True)
    s = np.asarray(m.weights.sum(axis=1)).ravel()
    assert set(np.nonzero(s > 0)[0]) == skinned


@needs_data
def test_rignet_mapping_follows_skin():
    """Weight of joint j goes to the bone leaving j: the thigh joint's vertices land on the bone
    from that joint towards the knee (2982: joint_0 → joint_5)."""
    rig = read_rignet_rig(RIGNET / "2982_ori_rig.txt")
    m = load_model(RIGNET / "2982_ori.obj", height_mm=None)
    b = m.bone_names.index("joint_0")
    j0, j5 = rig["names"].index("joint_0"), rig["names"].index("joint_5")
    np.testing.assert_allclose(m.heads[b], rig["positions"][j0])
    np.testing.assert_allclose(m.tails[b], rig["positions"][j5])
    # root has duplicates root_dup_K: each starts one bone; those bones are roots
    for k in range(4):
        i = m.bone_names.index(f"root_dup_{k}")
        assert m.parents[i] == -1
    # vertices whose largest skin weight is joint_0 get their largest bone weight on bone b
    best = {}
    for ln in (RIGNET / "2982_ori_rig.txt").read_text().splitlines():
        if ln.startswith("skin "):
            t = ln.split()
            js, ws = t[2::2], [float(x) for x in t[3::2]]
            best[int(t[1])] = js[int(np.argmax(ws))]
    W = m.weights.toarray()
    v0 = [v for v, j in best.items() if j == "joint_0"]
    assert len(v0) > 10
    assert np.all(W[v0].argmax(1) == b)


@needs_data
def test_gltf_fox():
    import pygltflib

    g = pygltflib.GLTF2().load(str(FOX))
    pos_acc = g.accessors[g.meshes[0].primitives[0].attributes.POSITION]
    m = load_model(FOX, height_mm=120)
    # unindexed flat-shaded → welded: fewer vertices, closed surface
    assert len(m.vertices) < pos_acc.count
    assert len(m.faces) == pos_acc.count // 3
    import trimesh

    t = trimesh.Trimesh(m.vertices, m.faces, process=False)
    assert t.is_watertight
    _assert_tree(m.parents)
    _assert_rows_sum_to_one(m.weights, allow_empty=True)
    assert np.all(np.asarray(m.weights.sum(axis=1)).ravel() > 0)
    # joints (via inverse bind matrices) become bone heads/tails; every weighted bone exists
    assert m.n_bones >= 20
    ibm = np.frombuffer(
        g.binary_blob(),
        dtype="<f4",
        count=16 * len(g.skins[0].joints),
        offset=(
            g.bufferViews[g.accessors[g.skins[0].inverseBindMatrices].bufferView].byteOffset or 0
        )
        + (g.accessors[g.skins[0].inverseBindMatrices].byteOffset or 0),
    ).reshape(-1, 4, 4)
    joint_pos = np.array([np.linalg.inv(M.T)[:3, 3] for M in ibm]) * m.scale
    for p in np.vstack([m.heads, m.tails]):
        assert np.min(np.linalg.norm(joint_pos - p, axis=1)) < 1e-3
    assert "b_Head_05" not in m.bone_names  # a leaf joint gives its weight to the bone ending at it
    assert "b_Neck_04" in m.bone_names


def test_weld_merges_duplicates():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.0]])
    F = np.array([[0, 1, 2], [3, 5, 4]])
    V2, F2, _o2n = weld(V, F)
    assert len(V2) == 4
    np.testing.assert_array_equal(V2[F2], V[F])


def test_scaling_and_axis():
    V = np.array([[0, 0, 0], [10, 0, 0], [0, 20, 0], [0, 0, 5.0]])
    F = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]])
    m = RiggedModel(V, F, [[0, 0, 0]], [[0, 10, 0]], [-1], ["b"])
    s = m.scaled_to(100.0)
    assert s.scale == pytest.approx(5.0)
    np.testing.assert_allclose(s.tails, [[0, 50, 0]])
    s = m.scaled_to(100.0, axis="z")
    assert s.scale == pytest.approx(20.0)
    with pytest.raises(ValueError, match="height_mm"):
        m.scaled_to(-1)


# ----------------------------------------------------------------------------- bad input


def test_missing_file(tmp_path):
    with pytest.raises(ValueError, match="not found"):
        load_model(tmp_path / "nope.obj")


def test_unknown_format(tmp_path):
    p = tmp_path / "x.xyz"
    p.write_text("1 2 3\n")
    with pytest.raises(ValueError, match="unknown mesh format"):
        load_model(p, skeleton=p)


@needs_data
def test_no_skeleton(tmp_path):
    V, F = read_mesh(LIBIGL / "arm.obj")
    p = tmp_path / "lonely.obj"
    write_mesh(p, V, F)
    with pytest.raises(ValueError, match="no skeleton"):
        load_model(p)


@needs_data
def test_weights_not_matching(tmp_path):
    w = tmp_path / "w.dmat"
    write_dmat(w, np.ones((10, 4)))
    with pytest.raises(ValueError, match="8311 vertices"):
        load_model(LIBIGL / "arm.obj", skeleton=LIBIGL / "arm.tgf", weights=w)


@pytest.mark.parametrize(
    "text,match",
    [
        ("1 0 0 0\n2 1 0 0\n#\n1 3\n#\n", "outside"),
        ("1 0 0 0\n2 1 0 0\n", "no bones"),
        ("1 0 zero 0\n#\n1 2\n#\n", "joint"),
        ("1 0 0 0\n2 1 0 0\n3 2 0 0\n#\n1 3\n2 3\n#\n", "two bones"),
        ("", "no joints"),
    ],
)
def test_bad_tgf(tmp_path, text, match):
    p = tmp_path / "bad.tgf"
    p.write_text(text)
    with pytest.raises(ValueError, match=match):
        read_tgf(p)


def test_bad_dmat(tmp_path):
    p = tmp_path / "bad.dmat"
    p.write_text("2 3\n1 2 3\n")
    with pytest.raises(ValueError, match="header says"):
        read_dmat(p)
    p.write_text("hello\n")
    with pytest.raises(ValueError, match="not a DMAT"):
        read_dmat(p)


def test_bad_rignet(tmp_path):
    p = tmp_path / "r_rig.txt"
    p.write_text("joints a 0 0 0\njoints b 0 1 0\nroot a\nhier a c\n")
    with pytest.raises(ValueError, match="undeclared joint"):
        read_rignet_rig(p)
    p.write_text("joints a 0 0 0\nbogus line\n")
    with pytest.raises(ValueError, match="not a RigNet rig line"):
        read_rignet_rig(p)
    p.write_text("joints a 0 0 0\njoints b 0 1 0\nhier a b\nhier b a\n")
    with pytest.raises(ValueError, match="two parents|cycle"):
        read_rignet_rig(p)


@needs_data
def test_rignet_vertex_out_of_range(tmp_path):
    p = tmp_path / "t_rig.txt"
    p.write_text("joints a 0 0 0\njoints b 0 1 0\nroot a\nhier a b\nskin 99999 a 1.0\n")
    with pytest.raises(ValueError, match="vertex 99999"):
        load_model(LIBIGL / "arm.obj", skeleton=p)


def test_bad_gltf(tmp_path):
    p = tmp_path / "x.glb"
    p.write_bytes(b"not a glb at all")
    with pytest.raises(ValueError):
        load_model(p)
