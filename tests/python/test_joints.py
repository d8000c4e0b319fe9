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


def test_correct_scales_across_the_given_long_axes():
    """A joint-rig bone scaled across its own local axis (bone_long_axes), not its segment: the
    corrected vertices are exactly ``skin`` with those axes (Blender's pose scale on them), and
    the correction still ends with no weak section (each round re-analyses the scaled mesh)."""
    import osteon
    from shapes import prism, rectangle

    v, f = prism(rectangle(6.0, 6.0), 60.0)
    v = np.asarray(v, float)
    # the head inside the bar (5 mm from its end cap): the cap, sheared by an off-segment
    # scale, is then not cut by the head's section (a plane through a tilted cap is a sliver)
    sk = osteon.Skeleton([[5, 0, 0]], [[60, 0, 0]], [-1], names=["bone"])
    w = np.ones((len(v), 1))
    before = osteon.analyze(v, f, sk, w, force=10.0, allowable_stress=60.0, interval=2.0)
    allowable = before.max_stress / 2
    # the bone's "length" axis 5 degrees off its segment, in the x-y plane; x axis across it
    # (far off, scaling across it also shears the bar: at 20 degrees its free end moves 5 mm
    # sideways and the load's lever arm grows faster than the section)
    a = np.radians(5.0)
    long_axis = np.array([[np.cos(a), np.sin(a), 0.0]])
    x_axis = np.array([[0.0, 0.0, 1.0]])
    fix = osteon.correct(v, f, sk, w, force=10.0, allowable_stress=allowable, interval=2.0,
                         bone_x_axes=x_axis, bone_long_axes=long_axis)
    assert fix.converged and fix.after.max_stress <= allowable
    assert fix.bone_scale[0] > 1.0
    again = osteon.skin(v, sk, w, fix.bone_scale_x, bone_scale_z=fix.bone_scale_z,
                        bone_x_axes=fix.bone_x_axis, bone_long_axes=long_axis)
    np.testing.assert_allclose(fix.vertices, again, rtol=0, atol=1e-12 * 60)
    # closed form of one vertex: scale s_x along x_axis, s_z along z = x × long, 1 along long
    z = np.cross(x_axis[0], long_axis[0])
    p = v[-1] - [5, 0, 0]
    want = [5, 0, 0] + (fix.bone_scale_x[0] * (p @ x_axis[0]) * x_axis[0]
                        + fix.bone_scale_z[0] * (p @ z) * z + (p @ long_axis[0]) * long_axis[0])
    np.testing.assert_allclose(fix.vertices[-1], want, atol=1e-9)
    # a long axis along the segment is the default, bit for bit
    plain = osteon.correct(v, f, sk, w, force=10.0, allowable_stress=allowable, interval=2.0)
    along = osteon.correct(v, f, sk, w, force=10.0, allowable_stress=allowable, interval=2.0,
                           bone_long_axes=[[2.0, 0.0, 0.0]])
    assert np.array_equal(plain.vertices, along.vertices)


@pytest.mark.parametrize("bad", [[[0.0, 0.0, 0.0]], [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
                                 [[np.nan, 0.0, 1.0]]])
def test_bad_long_axes_name_the_problem(bad):
    import osteon

    sk = osteon.Skeleton([[0, 0, 0]], [[1, 0, 0]], [-1])
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    with pytest.raises(ValueError, match="bone_long_axes"):
        osteon.correct(v, [[0, 1, 2]], sk, np.ones((3, 1)), bone_long_axes=bad)
    with pytest.raises(ValueError, match="bone_long_axes"):
        osteon.skin(v, sk, np.ones((3, 1)), [2.0], bone_long_axes=bad)
