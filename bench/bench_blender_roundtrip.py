"""Blender-side round trip on a ~100k-vertex rig: read the posed evaluated mesh ->
osteon analysis -> write the stress colour layer, against a baseline measured in the
same process (a bare ``foreach_get`` of the evaluated vertex coordinates).

    blender -b --factory-startup --python bench/bench_blender_roundtrip.py -- [--repeat 15]
    .venv-bpy/bin/python bench/bench_blender_roundtrip.py [--repeat 15]

The rig is the bundled sample figurine made denser (``--levels 3 --cuts 2``: 107k
vertices, 13 bones).  Each run first changes the pose (so the depsgraph really
re-evaluates the armature deformation, which is Blender's own work, timed apart), then
times, interleaved:

* ``baseline``   a bare foreach_get of the evaluated vertex coordinates into NumPy
                 (the ``position`` attribute in Blender 3.5+, else ``vertices.co``);
* ``read``       posed bones + evaluated mesh -> world-space mm arrays (bridge);
* ``analyze``    the engine on them: ``osteon.Analyzer.run`` (faces/weights kept, as the
                 live mode will) and a one-shot ``osteon.analyze``;
* ``write``      stress -> RGBA -> ``osteon_stress`` attribute (foreach_set);
* ``round trip`` read + Analyzer.run + write;
* ``operator``   the whole ``bpy.ops.osteon.analyze()`` (also reads the vertex-group
                 weights and triangulates: once per mesh edit, not per pose change).

Prints medians (ms) and each one's ratio to the baseline.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time

import bpy
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path[:0] = [os.path.join(ROOT, "blender_addon")]

import osteon
import osteon_blender
from osteon_blender import bridge, core
from osteon_blender import sample as make_sample_rig
from osteon_blender import service as common


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=15)
    ap.add_argument("--levels", type=int, default=3)
    ap.add_argument("--cuts", type=int, default=2)
    a = ap.parse_args(argv)

    if not hasattr(bpy.types.Scene, "osteon"):
        osteon_blender.register()
    obj, arm = make_sample_rig.build(a.levels, a.cuts)
    ctx = bpy.context
    s = ctx.scene.osteon
    nv = len(obj.data.vertices)

    t0 = time.perf_counter()
    inp = common.gather(ctx)  # weights + triangles + first read
    first_read = time.perf_counter() - t0
    sk0 = common.engine_skeleton(osteon, inp)
    analyzer = osteon.Analyzer(inp.faces, nv, sk0, inp.weights, **inp.params)
    allowable = inp.params["allowable_stress"]
    k = inp.mm_per_unit
    pb = arm.pose.bones["forearm.L"]
    pb.rotation_mode = "XYZ"

    names = ["depsgraph (Blender)", "baseline foreach_get", "read (bridge)",
             "analyze (Analyzer.run)", "analyze (osteon.analyze)", "write colours",
             "round trip", "operator osteon.analyze"]
    times: dict[str, list[float]] = {n: [] for n in names}
    co = np.empty(nv * 3, dtype=np.float32)
    for i in range(a.repeat + 1):
        pb.rotation_euler = (0.0, 0.0, 0.3 * math.sin(i))
        t = time.perf_counter()
        ctx.view_layer.update()
        depsgraph = ctx.evaluated_depsgraph_get()
        t_dg = time.perf_counter() - t

        t = time.perf_counter()
        me = obj.evaluated_get(depsgraph).data
        pos = me.attributes.get("position")
        if pos is not None:
            pos.data.foreach_get("vector", co)
        else:
            me.vertices.foreach_get("co", co)
        t_base = time.perf_counter() - t

        t = time.perf_counter()
        sk = bridge.skeleton_arrays(arm)
        verts = bridge.evaluated_positions(obj, depsgraph) * k
        skel = osteon.Skeleton(sk.heads * k, sk.tails * k, sk.parents, names=sk.names)
        t_read = time.perf_counter() - t

        t = time.perf_counter()
        res = analyzer.run(verts, skel)
        t_an = time.perf_counter() - t

        t = time.perf_counter()
        osteon.analyze(verts, inp.faces, skel, inp.weights, **inp.params)
        t_an1 = time.perf_counter() - t

        t = time.perf_counter()
        rgba = core.stress_colors(res.vertex_stress, allowable, res.vertex_culled)
        bridge.write_point_colors(obj.data, rgba)
        t_wr = time.perf_counter() - t

        t = time.perf_counter()
        assert bpy.ops.osteon.analyze() == {"FINISHED"}
        t_op = time.perf_counter() - t
        if i == 0:
            continue  # warm-up
        for n, v in zip(names, (t_dg, t_base, t_read, t_an, t_an1, t_wr,
                                t_read + t_an + t_wr, t_op)):
            times[n].append(v)

    base = statistics.median(times["baseline foreach_get"])
    print(f"\nBlender {bpy.app.version_string}, {'bpy module' if not bpy.app.binary_path else 'binary'}"
          f"; rig: {nv} vertices, {len(inp.faces)} triangles, {len(sk.names)} bones; "
          f"{len(res.stress)} sections at {s.interval_mm:g} mm; median of {a.repeat} runs")
    print(f"first read incl. vertex-group weights + triangulation: {first_read * 1e3:.1f} ms "
          f"(weights {inp.timings['read_weights_s'] * 1e3:.1f} ms)")
    print("| step | median (ms) | ratio to baseline |")
    print("|---|---|---|")
    for n in names:
        m = statistics.median(times[n])
        print(f"| {n} | {m * 1e3:.2f} | {m / base:.1f} |")
    rt = statistics.median(times["round trip"])
    print(f"ROUNDTRIP_MS={rt * 1e3:.2f} BASELINE_MS={base * 1e3:.3f} RATIO={rt / base:.1f}")
    osteon_blender.unregister()
    return 0


if __name__ == "__main__":
    if "--" in sys.argv:
        args = sys.argv[sys.argv.index("--") + 1:]
    else:
        args = [] if bpy.app.binary_path else sys.argv[1:]
    sys.exit(main(args))
