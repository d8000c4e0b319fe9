"""Live-mode update speed inside Blender: one live update (evaluated mesh -> analysis ->
``osteon_stress`` colour layer) on a ~100k-vertex rig, against a bare ``foreach_get`` of the
evaluated vertex coordinates in the same process.  Target (docs/method.md, Targets): <= 33 ms.

    blender -b --factory-startup --python bench/bench_live.py -- [--repeat 15]
    .venv-live/bin/python bench/bench_live.py -- [--repeat 15]      # the bpy 4.5 wheel

The rig is the bundled sample figurine (blender_addon/osteon_blender/sample.py ``--levels 3 --cuts 2``):
~107k vertices, 13 bones.  Each round changes a pose-bone scale (Blender evaluates the armature outside the
timed region), then times ``live.update_now()``; the overlay outlines are timed apart.
``--extra-shells 2`` adds an unweighted 'eye' inside the head and a 'prop' beside it (a
multi-shell character: the loose-piece search and nearest bones run on every update).
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import sys
import time

import bpy
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
for p in (os.path.join(ROOT, "blender_addon"), os.path.join(ROOT, "scripts"),
          os.path.join(ROOT, "tests", "blender")):
    if p not in sys.path:
        sys.path.insert(0, p)

import osteon_blender
from osteon_blender import live
from osteon_blender import sample as make_sample_rig


def add_shells(obj, count: int) -> None:
    """Adds `count` separate icospheres (642 vertices each, in no vertex group) to the mesh: an
    'eye' inside the head (attached: it lies inside the body) and a 'prop' beside the head (a
    loose piece). Live mode then runs the loose-piece search and binds them to their nearest
    bones on every update."""
    import bmesh
    from mathutils import Matrix

    co = np.empty(len(obj.data.vertices) * 3)
    obj.data.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3)
    top = co[:, 2].max()
    head = co[co[:, 2] > top - 0.1 * (top - co[:, 2].min())]
    eye = head.mean(axis=0)
    radius = 0.15 * float(np.ptp(head[:, 0]))
    centers = [eye, eye + np.array([co[:, 0].max() - eye[0] + 4 * radius, 0.0, 0.0])]
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    for c in centers[:count]:
        bmesh.ops.create_icosphere(bm, subdivisions=3, radius=radius,
                                   matrix=Matrix.Translation(tuple(c)))
    bm.to_mesh(obj.data)
    bm.free()
    obj.data.update()


def main(argv) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=15)
    ap.add_argument("--levels", type=int, default=3, help="Catmull-Clark levels of the rig")
    ap.add_argument("--cuts", type=int, default=2, help="extra edge cuts (3 + 2: ~107k vertices)")
    ap.add_argument("--no-junction-cores", action="store_true",
                    help="the add-on's 'Junction cores' off (whole cuts, docs/junctions.md)")
    ap.add_argument("--extra-shells", type=int, default=0, choices=(0, 1, 2),
                    help="separate unweighted shells added to the mesh: 1 an 'eye' inside the "
                         "head, 2 also a 'prop' floating beside it (a loose piece)")
    args = ap.parse_args(argv)
    import osteon

    if not hasattr(bpy.types.Scene, "osteon"):
        osteon_blender.register()
    obj, arm = make_sample_rig.build(levels=args.levels, cuts=args.cuts)
    if args.extra_shells:
        add_shells(obj, args.extra_shells)
    bpy.context.view_layer.objects.active = obj
    bpy.context.scene.osteon.junction_cores = not args.no_junction_cores
    nv = len(obj.data.vertices)
    live.start(bpy.context)
    sess = live.session()
    pb = arm.pose.bones["forearm.L"]
    buf = np.empty(nv * 3, dtype=np.float32)
    t_live, t_base, parts, t_out, faults = [], [], {}, [], []
    for i in range(args.repeat + 2):
        s = 0.7 + 0.02 * (i % 5)
        pb.scale = (s, 1.0, s)
        bpy.context.view_layer.update()             # Blender's armature evaluation: not timed
        dg = bpy.context.evaluated_depsgraph_get()
        t0 = time.perf_counter()
        obj.evaluated_get(dg).data.vertices.foreach_get("co", buf)
        t1 = time.perf_counter()
        before = sess.readout.updates
        f1 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        live.update_now(depsgraph=dg, outlines=False)
        t2 = time.perf_counter()
        f2 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        assert sess.readout.updates == before + 1, "no update ran"
        res = sess.last_result
        t3 = time.perf_counter()
        out = live.outlines_of(sess, res)
        t4 = time.perf_counter()
        if i < 2:                                    # warm-up
            continue
        t_base.append(t1 - t0)
        t_live.append(t2 - t1)
        t_out.append(t4 - t3)
        faults.append(f2 - f1)
        for k, v in res.timings.items():
            parts.setdefault(k, []).append(v)
    live.stop()
    med_live, med_base = statistics.median(t_live) * 1e3, statistics.median(t_base) * 1e3
    print(f"Blender {bpy.app.version_string}, engine {osteon.__file__}")
    print(f"rig: {nv} vertices ({args.extra_shells} extra shells), {len(sess.faces)} triangles, "
          f"{len(res.names)} bones, "
          f"{res.analysis.num_sections} sections at {res.analysis.interval:g} mm; "
          f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}; "
          f"{len(res.analysis.loose_pieces)} loose pieces")
    print(f"live update median      {med_live:8.2f} ms   (target <= 33 ms)")
    print(f"foreach_get median      {med_base:8.2f} ms")
    print(f"ratio update / foreach_get {med_live / med_base:6.1f}")
    # Fresh pages the process touched during an update (first-touch faults cost time the
    # instruction counts do not show; a buffer allocated anew on every update shows up here).
    print(f"page faults per update  {statistics.median(faults):8.0f} (median, minor)")
    for k, v in parts.items():
        print(f"  {k:<12} median {statistics.median(v):8.2f} ms")
    print(f"overlay outlines median {statistics.median(t_out) * 1e3:8.2f} ms "
          f"({out.num_sections} sections; computed after the colours, in the worker)")
    return 0


if __name__ == "__main__":
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    code = main(argv)
    if not bpy.app.binary_path:          # the bpy wheel: unregister or it hangs at exit
        osteon_blender.unregister()
    sys.exit(code)
