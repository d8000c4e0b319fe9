"""Loose pieces in Blender: the Analyze report names them, osteon.select_loose_pieces selects
their vertices (Edit Mode) on the analysed mesh."""

import bpy
import numpy as np
import pytest
from osteon_blender import bridge, state


def _add_detached_cube(obj) -> np.ndarray:
    """Append an 8-vertex cube well apart from the mesh (weighted to its first bone); returns
    the cube's vertex indices."""
    import bmesh  # after bpy: the bpy wheel provides it only then

    me = obj.data
    n0 = len(me.vertices)
    co = bridge.local_positions(me)
    lo, hi = co.min(axis=0), co.max(axis=0)
    size = float((hi - lo).max())
    bm = bmesh.new()
    bm.from_mesh(me)
    centre = hi + np.array([0.5 * size, 0.0, 0.0])
    centre[2] = 0.5 * (lo[2] + hi[2])
    bmesh.ops.create_cube(bm, size=0.1 * size,
                          matrix=__import__("mathutils").Matrix.Translation(tuple(centre)))
    bm.to_mesh(me)
    bm.free()
    me.update()
    cube = np.arange(n0, len(me.vertices))
    obj.vertex_groups[0].add(cube.tolist(), 1.0, "REPLACE")
    return cube


def _selected(obj) -> np.ndarray:
    if obj.mode != "OBJECT":
        bpy.ops.object.mode_set(mode="OBJECT")
    sel = np.zeros(len(obj.data.vertices), dtype=bool)
    obj.data.vertices.foreach_get("select", sel)
    return np.flatnonzero(sel)


def test_select_loose_pieces_selects_the_detached_cube(sample, engine):
    obj, _arm = sample
    cube = _add_detached_cube(obj)
    assert len(cube) == 8
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    info = state.get(bpy.context.scene).loose_pieces
    assert info["object"] == obj.name
    assert [sorted(p.tolist()) for p in info["pieces"]] == [cube.tolist()]
    report = state.get(bpy.context.scene).last["report"]
    assert len(report["loose_pieces"]) == 1 and report["loose_pieces"][0]["vertices"] == 8
    from osteon_blender import service

    assert "1 loose piece would fall off the print: 8 vertices" in service.summary(report)
    # everything selected first: the operator leaves exactly the cube selected
    bridge.select_vertices(obj.data, np.arange(len(obj.data.vertices)))
    assert bpy.ops.osteon.select_loose_pieces() == {"FINISHED"}
    assert obj.mode == "EDIT"
    assert bpy.context.view_layer.objects.active == obj
    np.testing.assert_array_equal(_selected(obj), cube)


def test_select_loose_pieces_without_result(addon):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    with pytest.raises(RuntimeError, match="run Analyze first"):
        bpy.ops.osteon.select_loose_pieces()


def test_no_loose_pieces_selects_nothing_new(sample, engine):
    obj, _arm = sample
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    assert state.get(bpy.context.scene).loose_pieces["pieces"] == []
    assert bpy.ops.osteon.select_loose_pieces() == {"FINISHED"}
    assert obj.mode == "OBJECT"
