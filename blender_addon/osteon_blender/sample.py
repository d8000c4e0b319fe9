"""Build osteon's bundled sample rigged model from primitives, inside Blender.

A little figurine (torso, head, two arms, two legs, a thin antenna and a thin
tail) made as ONE closed mesh with Blender's Skin modifier, an armature whose
bones follow the limbs, and distance-based vertex-group weights (deterministic,
no bone-heat solver).  At osteon's default load (20 N, PLA, safety factor 2,
printed height 120 mm) the antenna and the tail come out weak, the body safe.

Run:
    blender -b --factory-startup --python blender_addon/osteon_blender/sample.py -- \
        --out out/sample_rig.blend [--levels 2] [--cuts 0]

``--levels L`` (Catmull-Clark levels of the skin, default 2: 2987 vertices) and
``--cuts C`` (extra edge cuts per quad edge, x(C+1)^2 faces) make denser copies of the
same shape: ``--levels 3 --cuts 2`` gives ~107k vertices for the benchmark.  Weights
are computed from the final geometry.  Works in Blender 3.4+ and in the ``bpy``
wheel (``python blender_addon/osteon_blender/sample.py -- --out ...``).
"""

from __future__ import annotations

import argparse
import os
import sys

import bpy
import numpy as np

# joint name -> (position in Blender units, skin radius)
JOINTS = {
    "pelvis": ((0.0, 0.0, 1.00), 0.15),
    "chest": ((0.0, 0.0, 1.50), 0.17),
    "neck": ((0.0, 0.0, 1.70), 0.075),
    "head_c": ((0.0, 0.0, 1.90), 0.20),
    "head_top": ((0.0, 0.0, 2.08), 0.055),
    "antenna_tip": ((0.09, 0.0, 2.45), 0.027),
    "tail_base": ((0.0, 0.12, 0.98), 0.06),
    "tail_tip": ((0.0, 0.78, 0.86), 0.032),
}
for side, sx in (("L", 1.0), ("R", -1.0)):
    JOINTS.update({
        f"shoulder.{side}": ((0.24 * sx, 0.0, 1.55), 0.085),
        f"elbow.{side}": ((0.52 * sx, 0.0, 1.36), 0.07),
        f"wrist.{side}": ((0.77 * sx, 0.0, 1.16), 0.065),
        f"hip.{side}": ((0.12 * sx, 0.0, 0.98), 0.11),
        f"knee.{side}": ((0.15 * sx, 0.0, 0.55), 0.09),
        f"ankle.{side}": ((0.16 * sx, 0.0, 0.08), 0.085),
    })

EDGES = [
    ("pelvis", "chest"), ("chest", "neck"), ("neck", "head_c"), ("head_c", "head_top"),
    ("head_top", "antenna_tip"), ("pelvis", "tail_base"), ("tail_base", "tail_tip"),
]
for s in ("L", "R"):
    EDGES += [
        ("chest", f"shoulder.{s}"), (f"shoulder.{s}", f"elbow.{s}"), (f"elbow.{s}", f"wrist.{s}"),
        ("pelvis", f"hip.{s}"), (f"hip.{s}", f"knee.{s}"), (f"knee.{s}", f"ankle.{s}"),
    ]

# bone name -> (head joint, tail joint, parent bone or None)
BONES = {
    "spine": ("pelvis", "chest", None),
    "neck": ("chest", "neck", "spine"),
    "head": ("neck", "head_top", "neck"),
    "antenna": ("head_top", "antenna_tip", "head"),
    "tail": ("tail_base", "tail_tip", "spine"),
}
for s in ("L", "R"):
    BONES.update({
        f"upper_arm.{s}": (f"shoulder.{s}", f"elbow.{s}", "spine"),
        f"forearm.{s}": (f"elbow.{s}", f"wrist.{s}", f"upper_arm.{s}"),
        f"thigh.{s}": (f"hip.{s}", f"knee.{s}", "spine"),
        f"shin.{s}": (f"knee.{s}", f"ankle.{s}", f"thigh.{s}"),
    })


#: a bone that ends a limb stops this many skin radii of its end joint inside the mesh: the
#: Skin modifier's rounded, subdivided end cap lies inside the joint's sphere, and a bone
#: reaching past it has sections that cut nothing (the analysis would rightly flag them)
LEAF_INSET_RADII = 1.5


def bone_segments() -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Bone name -> (head, tail) in Blender units: the joints, with the bones that end a limb
    (no child bone) shortened by LEAF_INSET_RADII radii of their end joint."""
    parents = {p for _h, _t, p in BONES.values() if p is not None}
    out = {}
    for b, (h, t, _p) in BONES.items():
        head, tail = np.array(JOINTS[h][0]), np.array(JOINTS[t][0])
        if b not in parents:
            axis = tail - head
            tail = tail - axis / np.linalg.norm(axis) * LEAF_INSET_RADII * JOINTS[t][1]
        out[b] = (head, tail)
    return out


def _segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ab = b - a
    t = np.clip(((p - a) @ ab) / float(ab @ ab), 0.0, 1.0)
    return np.linalg.norm(p - (a + t[:, None] * ab), axis=1)


def distance_weights(co: np.ndarray, segments: list[tuple[np.ndarray, np.ndarray]],
                     blend: float = 0.04) -> np.ndarray:
    """(V, B) weights: nearest bone 1, neighbours fading out within ``blend`` units."""
    d = np.stack([_segment_distance(co, a, b) for a, b in segments], axis=1)
    rel = d - d.min(axis=1, keepdims=True)
    w = np.clip(1.0 - rel / blend, 0.0, None) ** 2
    return w / w.sum(axis=1, keepdims=True)


def build(levels: int = 2, cuts: int = 0, name: str = "Figurine") -> tuple[bpy.types.Object, bpy.types.Object]:
    scene = bpy.context.scene
    for ob in list(bpy.data.objects):
        bpy.data.objects.remove(ob, do_unlink=True)

    names = list(JOINTS)
    index = {n: i for i, n in enumerate(names)}
    graph = bpy.data.meshes.new(name + "_skeleton")
    graph.from_pydata([JOINTS[n][0] for n in names], [(index[a], index[b]) for a, b in EDGES], [])
    graph.update()
    skin_obj = bpy.data.objects.new(name + "_skin", graph)
    scene.collection.objects.link(skin_obj)
    skin_obj.modifiers.new("Skin", "SKIN")
    skin_layer = graph.skin_vertices[0].data
    for n, i in index.items():
        r = JOINTS[n][1]
        skin_layer[i].radius = (r, r)
        skin_layer[i].use_root = n == "pelvis"
    sub = skin_obj.modifiers.new("Subdivision", "SUBSURF")
    sub.levels = sub.render_levels = levels
    depsgraph = bpy.context.evaluated_depsgraph_get()
    mesh = bpy.data.meshes.new_from_object(skin_obj.evaluated_get(depsgraph))
    mesh.name = name
    bpy.data.objects.remove(skin_obj, do_unlink=True)
    bpy.data.meshes.remove(graph)
    if cuts > 0:
        import bmesh  # after bpy: the bpy wheel provides it only then

        bm = bmesh.new()
        bm.from_mesh(mesh)
        bmesh.ops.subdivide_edges(bm, edges=bm.edges[:], cuts=cuts, use_grid_fill=True)
        bm.to_mesh(mesh)
        bm.free()
    for poly in mesh.polygons:
        poly.use_smooth = True

    # armature
    arm_data = bpy.data.armatures.new(name + "_rig")
    arm = bpy.data.objects.new(name + "_rig", arm_data)
    scene.collection.objects.link(arm)
    bpy.context.view_layer.objects.active = arm
    bpy.ops.object.mode_set(mode="EDIT")
    segments = bone_segments()
    for bname in BONES:
        eb = arm_data.edit_bones.new(bname)
        eb.head = tuple(segments[bname][0])
        eb.tail = tuple(segments[bname][1])
        eb.roll = 0.0
    for bname, (h, _t, p) in BONES.items():
        if p is not None:
            eb = arm_data.edit_bones[bname]
            eb.parent = arm_data.edit_bones[p]
            eb.use_connect = BONES[p][1] == h
    bpy.ops.object.mode_set(mode="OBJECT")

    obj = bpy.data.objects.new(name, mesh)
    scene.collection.objects.link(obj)
    obj.parent = arm
    mod = obj.modifiers.new("Armature", "ARMATURE")
    mod.object = arm

    co = np.empty(len(mesh.vertices) * 3)
    mesh.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3)
    bone_names = list(BONES)
    segs = [(np.array(JOINTS[BONES[b][0]][0]), np.array(JOINTS[BONES[b][1]][0])) for b in bone_names]
    w = distance_weights(co, segs)
    for j, bname in enumerate(bone_names):
        vg = obj.vertex_groups.new(name=bname)
        nz = np.flatnonzero(w[:, j] > 1e-6)
        full = nz[w[nz, j] >= 1.0 - 1e-9]
        if len(full):
            vg.add(full.tolist(), 1.0, "REPLACE")
        for i in np.setdiff1d(nz, full):
            vg.add([int(i)], float(w[i, j]), "REPLACE")

    for o in scene.objects:
        o.select_set(False)
    obj.select_set(True)
    bpy.context.view_layer.objects.active = obj
    return obj, arm


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="output .blend path")
    ap.add_argument("--levels", type=int, default=2, help="subdivision levels of the skin")
    ap.add_argument("--cuts", type=int, default=0, help="extra cuts per edge")
    args = ap.parse_args(argv)
    obj, _arm = build(args.levels, args.cuts)
    out = os.path.abspath(args.out)
    os.makedirs(os.path.dirname(out), exist_ok=True)
    bpy.ops.wm.save_as_mainfile(filepath=out, check_existing=False)
    print(f"sample rig: {len(obj.data.vertices)} vertices, {len(obj.vertex_groups)} groups -> {out}")
    return 0


if __name__ == "__main__":
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    sys.exit(main(argv))
