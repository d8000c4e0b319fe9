"""The add-on's Make skeleton operator on cow ×4 (93 k faces), inside Blender (issue 35).

Times ``bpy.ops.osteon.make_skeleton()`` on the cow subdivided once (scaled to 120 mm) over
--repeat runs after a first one (each run starts from the bare mesh: the armature, its modifier
and the vertex groups of the run before are removed), then one profiled run's CPU per step:
reading the mesh, ``osteon.auto_skeleton``, building the armature, writing the vertex groups,
binding. Reads tests/data (or OSTEON_DATA).

    blender -b --factory-startup --python bench/bench_make_skeleton.py -- [--repeat 3]
    .venv-bpy/bin/python bench/bench_make_skeleton.py [--repeat 3]
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import statistics
import sys
import time
from pathlib import Path

import bpy
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "blender_addon"))
sys.path.insert(0, str(ROOT / "bench"))


def cow_object():
    """The cow ×4 as a mesh object, active and selected."""
    from models import load

    v, f, _, _ = load("cow", subdivisions=1)
    me = bpy.data.meshes.new("cow4")
    me.vertices.add(len(v))
    me.vertices.foreach_set("co", np.asarray(v, np.float32).ravel())
    me.loops.add(3 * len(f))
    me.loops.foreach_set("vertex_index", np.asarray(f, np.int32).ravel())
    me.polygons.add(len(f))
    me.polygons.foreach_set("loop_start", np.arange(0, 3 * len(f), 3, dtype=np.int32))
    if hasattr(me.polygons[0], "loop_total") and bpy.app.version < (4, 0, 0):
        me.polygons.foreach_set("loop_total", np.full(len(f), 3, np.int32))
    me.update()
    obj = bpy.data.objects.new("cow4", me)
    bpy.context.collection.objects.link(obj)
    return obj


def reset(obj) -> None:
    """Back to the bare mesh: no Armature modifier, vertex groups or skeleton objects."""
    for m in list(obj.modifiers):
        obj.modifiers.remove(m)
    obj.vertex_groups.clear()
    for o in list(bpy.data.objects):
        if o.type == "ARMATURE":
            bpy.data.objects.remove(o)
    for a in list(bpy.data.armatures):
        bpy.data.armatures.remove(a)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)


def main() -> None:
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    import osteon_blender

    if not hasattr(bpy.types.Scene, "osteon"):
        osteon_blender.register()
    obj = cow_object()
    reset(obj)
    bpy.ops.osteon.make_skeleton()  # the first run imports pygel3d and warms caches
    wall, cpu = [], []
    for _ in range(args.repeat):
        reset(obj)
        t, c = time.perf_counter(), time.process_time()
        bpy.ops.osteon.make_skeleton()
        wall.append(time.perf_counter() - t)
        cpu.append(time.process_time() - c)
    print(f"Blender {bpy.app.version_string}: Make skeleton on cow x4 ({len(obj.data.polygons)} "
          f"faces): median {statistics.median(wall):.2f} s wall, {statistics.median(cpu):.2f} s "
          f"CPU over {args.repeat} runs")
    reset(obj)
    prof = cProfile.Profile(time.process_time)
    prof.runcall(bpy.ops.osteon.make_skeleton)
    stats = pstats.Stats(prof).stats
    steps = {"world_rest_positions": "read positions", "triangles": "read faces",
             "auto_skeleton": "auto_skeleton", "build_armature": "armature",
             "write_bone_weights": "vertex groups", "bind_armature": "bind",
             "run_make_skeleton": "operator in all"}
    print("steps (CPU s, one profiled run):", ", ".join(
        f"{label} {sum(st[3] for key, st in stats.items() if key[2] == fn):.3f}"
        for fn, label in steps.items()))


main()
