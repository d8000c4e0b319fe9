"""Joint rigs → bone segments (issue 13): the one function the Blender bridge calls
(``osteon.io.joints.joint_segments``) gives, on a rig made of joints, the segments the RigNet and
glTF readers give the engine for the same file (to 1e-6 of the model size)."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import DATA
from osteon.io import joints
from osteon.io.gltf import read_gltf, read_gltf_joints
from osteon.io.loader import read_mesh
from osteon.io.rignet import read_rignet_rig, rignet_skeleton

DOG = DATA / "RigNet" / "2982_ori"
FOX = DATA / "glTF-Sample-Models" / "Fox.glb"


def _compare(reader_heads, reader_tails, reader_names, heads, tails, names, size):
    """Every reader bone named after a joint has that joint's segment."""
    idx = {n: i for i, n in enumerate(names)}
    checked = 0
    for h, t, n in zip(reader_heads, reader_tails, reader_names):
        if n not in idx:  # an edge of a branching joint ("a->b"): the joint's one bone runs
            a = idx[n.split("->")[0]]  # along one of its edges, from the same head
            assert np.abs(heads[a] - h).max() <= 1e-6 * size, n
            continue
        j = idx[n]
        assert np.abs(heads[j] - h).max() <= 1e-6 * size, n
        assert np.abs(tails[j] - t).max() <= 1e-6 * size, n
        checked += 1
    return checked


def test_rignet_reader_and_joint_segments_agree():
    rig = read_rignet_rig(f"{DOG}_rig.txt")
    v, _ = read_mesh(f"{DOG}.obj")
    rh, rt, _, rnames, _ = rignet_skeleton(rig, v)
    heads, tails, _, _, changed = joints.joint_rig_bones(
        rig["positions"], rig["parent"], rig["skin_rows"], rig["skin_joints"],
        rig["skin_values"], len(v), v)
    size = float(np.ptp(v, axis=0).max())
    n = _compare(rh, rt, rnames, heads, tails, rig["names"], size)
    assert n == sum("->" not in x for x in rnames) and n >= 15
    assert changed.sum() >= n  # every stub tail was replaced


def test_gltf_reader_and_joint_segments_agree():
    j = read_gltf_joints(FOX)
    _, _, rh, rt, _, rnames, _ = read_gltf(FOX)
    heads, tails, _, _, _ = joints.joint_rig_bones(
        j["positions"], j["parent"], j["skin_rows"], j["skin_joints"], j["skin_values"],
        len(j["vertices"]), j["vertices"])
    size = float(np.ptp(j["vertices"], axis=0).max())
    n = _compare(rh, rt, rnames, heads, tails, j["names"], size)
    assert n == sum("->" not in x for x in rnames) and n >= 10
    # a branching joint's bone runs to one of its children (the one its domain lies towards)
    for x in rnames:
        if "->" in x:
            a = j["names"].index(x.split("->")[0])
            kids = np.flatnonzero(j["parent"] == a)
            assert min(np.abs(heads[k] - tails[a]).max() for k in kids) <= 1e-6 * size


def test_bone_rig_is_left_alone():
    heads = np.array([[0, 0, 0], [0, 0, 1], [0, 0, 2]], float)
    tails = np.array([[0, 0, 1], [0, 0, 2], [0, 0, 2.5]], float)
    par = np.array([-1, 0, 1])
    assert not joints.is_joint_rig(heads, tails, par)
    out, changed = joints.joint_segments(heads, tails, par)
    assert not changed.any() and np.array_equal(out, tails)


def test_leaf_runs_to_the_far_end_of_its_domain():
    """Two joints on the x axis, bones pointing up (+z) as FBX imports them; the leaf's
    vertices run from x=1 to x=3: its segment runs towards them, to their mean distance."""
    heads = np.array([[0, 0, 0], [1, 0, 0]], float)
    tails = heads + [0, 0, 0.3]
    par = np.array([-1, 0])
    xs = np.linspace(0, 3, 31)
    v = np.column_stack([xs, 0.1 * np.cos(7 * xs), 0.1 * np.sin(7 * xs)])
    w = np.zeros((len(v), 2))
    w[xs < 1, 0] = 1.0
    w[xs >= 1, 1] = 1.0
    out, changed = joints.joint_segments(heads, tails, par, v, w)
    assert changed.all()
    np.testing.assert_allclose(out[0], [1, 0, 0])  # joint -> child joint
    d = (out[1] - heads[1]) / np.linalg.norm(out[1] - heads[1])
    c = (v[xs >= 1].mean(0) - heads[1])
    np.testing.assert_allclose(d, c / np.linalg.norm(c), atol=1e-12)
    # it reaches LEAF_FACTOR of the domain's weighted mean distance (LEAF_REACH = "centroid")
    assert (out[1] - heads[1]) @ d == pytest.approx(
        joints.LEAF_FACTOR * ((v[xs >= 1] - heads[1]) @ d).mean())


def test_cross_section_axes_pick_the_axis_along_the_segment():
    ax = np.repeat(np.eye(3)[None], 3, axis=0)  # local X, Y, Z = world x, y, z
    seg = np.array([[0, 1, 0], [1, 0, 0], [0, 0.1, 1]], float)
    x, slots = joints.cross_section_axes(seg, ax)
    assert slots.tolist() == [[0, 2, 1], [1, 2, 0], [0, 1, 2]]
    np.testing.assert_allclose(x, [[1, 0, 0], [0, 1, 0], [1, 0, 0]])
