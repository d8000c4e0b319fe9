"""Live-mode update speed inside Blender, end to end and split by part: one live update (evaluated
mesh -> analysis -> ``osteon_stress`` colour layer, readout, panel, redraw tags) of the sample
figurine, against a bare ``foreach_get`` of the evaluated vertex coordinates in the same process.
Target (issue 34): the whole update <= 16 ms, the engine <= 10 ms.

    .venv-bpy/bin/python bench/bench_live.py -- [--repeat 21]      # the bpy 4.5 wheel
    .venv-bpy52/bin/python bench/bench_live.py -- [--repeat 21]    # the bpy 5.2 wheel
    blender -b --factory-startup --python bench/bench_live.py -- [--repeat 21]
    ... bench_live.py -- --capture live.npz      # also keep the engine's inputs of every update
    ... bench_live.py -- --profile live.prof     # cProfile of the updates (Python side)
    .venv/bin/python bench/bench_live.py --replay live.npz --instructions   # no bpy: callgrind
    ... --replay live.npz --dump reused.npz [--fresh]   # every number; --fresh: one-off runs

The rig is the bundled sample figurine (blender_addon/osteon_blender/sample.py ``--levels 3
--cuts 2``): ~107k vertices, 13 bones.  Each round changes a pose-bone scale (``--pose bend``:
its rotation; Blender evaluates the armature outside the timed region), then times ``live.update_now()``; the overlay outlines
are timed apart.  Per part, the process CPU time (``time.process_time``: all threads, so
the engine's workers count; the load of other processes does not) of the functions the update
calls, each part exclusive of the parts it calls, medians over the rounds; "rest" is what the
named parts leave of the update.  ``--extra-shells 2`` adds an unweighted 'eye' inside the head
and a 'prop' beside it (a multi-shell character: the loose-piece search and nearest bones run on
every update).

``--replay FILE``: the captured updates run again in a plain Python with the engine alone (the
same ``Analyzer`` inputs, no bpy); ``--instructions`` counts the machine instructions of one
update under valgrind's callgrind ((N runs - 2 runs) / (N - 2): the updates after the first,
which also fills what later ones reuse),
exact whatever the machine's load, and lists the engine stages' inclusive counts;
``OSTEON_OTHER_BUILD=DIR`` replays with another build's ``osteon`` package (a directory holding it
with its compiled ``_core``, as bench/compare_builds.py takes).
"""

from __future__ import annotations

import argparse
import ast
import math
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# (module path, attribute, part name): what an update calls, by part (main thread: read;
# worker: compute; main thread: publish)
PARTS = (
    ("osteon_blender.bridge", "skeleton_arrays", "read: pose bones"),
    ("osteon_blender.core", "engine_params", "read: engine params"),
    ("osteon_blender.core", "settings_of", "read: settings"),
    ("osteon_blender.bridge", "evaluated_positions_into", "read: positions"),
    ("osteon_blender.bridge", "topology_key", "read: topology key"),
    ("osteon_blender.bridge", "use_joint_segments", "compute: joint segments"),
    ("osteon.Analyzer", "run", "compute: engine (Python side)"),
    ("osteon._core.Analyzer", "run", "compute: engine"),
    ("osteon_blender.core", "build_report", "compute: report"),
    ("osteon_blender.results", "not_analysed_vertices", "compute: not analysed"),
    ("osteon_blender.core", "result_colors", "compute: colours"),
    ("osteon_blender.bridge", "write_point_colors", "publish: colour layer"),
    ("osteon_blender.results", "show", "publish: panel"),
    ("osteon_blender.bridge", "tag_redraw_view3d", "publish: redraw tags"),
)


class PartClock:
    """Wraps functions to add up their CPU and wall time per part, exclusive of nested parts."""

    def __init__(self):
        self.cpu: dict[str, float] = {}
        self.wall: dict[str, float] = {}
        self._stack: list[list[float]] = []
        self._undo: list[tuple] = []

    def wrap(self, owner, attr: str, name: str) -> None:
        fn = getattr(owner, attr)

        def timed(*a, **k):
            self._stack.append([0.0, 0.0])
            c0, w0 = time.process_time(), time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                dc, dw = time.process_time() - c0, time.perf_counter() - w0
                kc, kw = self._stack.pop()
                self.cpu[name] = self.cpu.get(name, 0.0) + dc - kc
                self.wall[name] = self.wall.get(name, 0.0) + dw - kw
                if self._stack:
                    self._stack[-1][0] += dc
                    self._stack[-1][1] += dw

        setattr(owner, attr, timed)
        self._undo.append((owner, attr, fn))

    def reset(self) -> None:
        self.cpu.clear()
        self.wall.clear()

    def unwrap(self) -> None:
        for owner, attr, fn in reversed(self._undo):
            setattr(owner, attr, fn)
        self._undo.clear()


def _resolve(path: str):
    import importlib

    mod, _, rest = path.partition(".")
    obj = importlib.import_module(mod)
    for part in rest.split(".") if rest else []:
        try:
            obj = getattr(obj, part)
        except AttributeError:
            obj = importlib.import_module(f"{obj.__name__}.{part}")
    return obj


class Capture:
    """Keeps the engine's inputs: the Analyzer's construction and every run's vertices."""

    def __init__(self, osteon):
        self.init, self.runs = None, []
        init0, run0 = osteon.Analyzer.__init__, osteon.Analyzer.run
        cap = self

        def init(self_, faces, num_vertices, skeleton, weights=None, **kw):
            cap.init = (np.asarray(faces), int(num_vertices), skeleton, weights, kw)
            return init0(self_, faces, num_vertices, skeleton, weights, **kw)

        def run(self_, vertices, skeleton=None, **kw):
            sk = skeleton if skeleton is not None else self_._skeleton
            cap.runs.append((np.array(vertices, dtype=np.float64), sk.heads.copy(),
                             sk.tails.copy()))
            return run0(self_, vertices, skeleton, **kw)

        osteon.Analyzer.__init__, osteon.Analyzer.run = init, run

    def save(self, path: str) -> None:
        import scipy.sparse as sp

        faces, nv, sk, w, kw = self.init
        w = sp.csr_matrix(w)
        np.savez(path, faces=faces, nv=nv, parents=sk.parents, names=np.array(sk.names or []),
                 w_data=w.data, w_indices=w.indices, w_indptr=w.indptr, w_shape=w.shape,
                 kw=np.array(repr(kw)),
                 vertices=np.stack([r[0] for r in self.runs]),
                 heads=np.stack([r[1] for r in self.runs]),
                 tails=np.stack([r[2] for r in self.runs]))


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


def _ms(values) -> str:
    return f"{statistics.median(values) * 1e3:8.2f}"


def main_blender(args) -> int:
    import bpy

    for p in (os.path.join(ROOT, "blender_addon"),):
        if p not in sys.path:
            sys.path.insert(0, p)
    import osteon
    import osteon_blender
    from osteon_blender import live
    from osteon_blender import sample as make_sample_rig

    if not hasattr(bpy.types.Scene, "osteon"):
        osteon_blender.register()
    cap = Capture(osteon) if args.capture else None
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
    clock = PartClock()
    prof = None
    if args.profile:        # cProfile of the timed updates instead of the part clocks
        import cProfile

        prof = cProfile.Profile()
    else:
        for path, attr, name in PARTS:
            clock.wrap(_resolve(path), attr, name)
    wall, cpu, base, out_t, faults = [], [], [], [], []
    parts_cpu: dict[str, list] = {}
    parts_wall: dict[str, list] = {}
    try:
        for i in range(args.repeat + 2):
            if args.pose == "bend":            # the elbow bent, 4-40 degrees in 10 steps
                pb.rotation_mode = "XYZ"
                pb.rotation_euler = (math.radians(4.0 * (1 + i % 10)), 0.0, 0.0)
            else:                               # the forearm thinned, 0.70-0.78 in 5 steps
                s = 0.7 + 0.02 * (i % 5)
                pb.scale = (s, 1.0, s)
            bpy.context.view_layer.update()             # Blender's armature evaluation: not timed
            dg = bpy.context.evaluated_depsgraph_get()
            before = sess.readout.updates
            f1 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
            clock.reset()
            if prof is not None and i >= 2:
                prof.enable()
            c1, t1 = time.process_time(), time.perf_counter()
            live.update_now(depsgraph=dg, outlines=False)
            c2, t2 = time.process_time(), time.perf_counter()
            if prof is not None:
                prof.disable()
            f2 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
            # the reference read after the update: before it, it would pay the first access
            # to the freshly evaluated mesh that a live update pays (in bpy 4.5 ~0.1 ms)
            t0 = time.perf_counter()
            obj.evaluated_get(dg).data.vertices.foreach_get("co", buf)
            t0 = time.perf_counter() - t0
            assert sess.readout.updates == before + 1, "no update ran"
            res = sess.last_result
            t3 = time.perf_counter()
            out = live.outlines_of(sess, res)
            t4 = time.perf_counter()
            if i < 2:                                    # warm-up
                continue
            base.append(t0)
            wall.append(t2 - t1)
            cpu.append(c2 - c1)
            out_t.append(t4 - t3)
            faults.append(f2 - f1)
            for k in [p[2] for p in PARTS] + ["rest"]:
                if k == "rest":
                    parts_cpu.setdefault(k, []).append((c2 - c1) - sum(clock.cpu.values()))
                    parts_wall.setdefault(k, []).append((t2 - t1) - sum(clock.wall.values()))
                else:
                    parts_cpu.setdefault(k, []).append(clock.cpu.get(k, 0.0))
                    parts_wall.setdefault(k, []).append(clock.wall.get(k, 0.0))
    finally:
        clock.unwrap()
    live.stop()
    print(f"Blender {bpy.app.version_string} (Python {sys.version.split()[0]}), "
          f"engine {osteon.__file__}")
    print(f"rig: {nv} vertices ({args.extra_shells} extra shells), {len(sess.faces)} triangles, "
          f"{len(res.names)} bones, "
          f"{res.analysis.num_sections} sections at {res.analysis.interval:g} mm; "
          f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}; "
          f"{len(res.analysis.loose_pieces)} loose pieces; {args.repeat} rounds")
    print(f"live update, CPU time   {_ms(cpu)} ms   (target <= 16 ms end to end)")
    print(f"live update, wall clock {_ms(wall)} ms")
    print(f"foreach_get of 'co'     {_ms(base)} ms (wall)")
    # Fresh pages the process touched during an update (first-touch faults cost time the
    # instruction counts do not show; a buffer allocated anew on every update shows up here).
    print(f"page faults per update  {statistics.median(faults):8.0f} (median, minor)")
    print("| part | CPU ms (median) | wall ms (median) |")
    print("|---|---|---|")
    for k, v in parts_cpu.items():
        print(f"| {k} | {_ms(v).strip()} | {_ms(parts_wall[k]).strip()} |")
    print(f"overlay outlines median {_ms(out_t)} ms wall "
          f"({out.num_sections} sections; computed after the colours, in the worker)")
    if prof is not None:
        import pstats

        prof.dump_stats(args.profile)
        pstats.Stats(prof).sort_stats("tottime").print_stats(40)
    if cap is not None:
        cap.save(args.capture)
        print(f"engine inputs of {len(cap.runs)} runs saved to {args.capture}")
    return 0


# --------------------------------------------------------------------------- replay (no bpy)

REPLAY_STAGES = (   # the run's stages (analysis.cpp) and the largest parts inside them
    "osteon::Analyzer::Impl::check_inputs", "osteon::Analyzer::Impl::assign_vertex_bones",
    "osteon::Analyzer::Impl::plan_sections", "osteon::Analyzer::Impl::reuse_last_run",
    "osteon::Analyzer::Impl::prepare_cuts", "osteon::FaceGrid::build",
    "osteon::Analyzer::Impl::cut_local", "osteon::Analyzer::Impl::cut_retries",
    "osteon::LoosePieceFinder::find", "osteon::MomentArmIndex::build",
    "osteon::Analyzer::Impl::find_junction_cores", "osteon::Analyzer::Impl::compute_loads",
    "osteon::find_notches", "osteon::Analyzer::Impl::compute_vertex_stress",
    "osteon::Analyzer::Impl::remember_inputs",
)


def _load(path: str):
    import scipy.sparse as sp

    if os.environ.get("OSTEON_OTHER_BUILD"):     # another build (as bench/compare_builds.py)
        sys.meta_path = [f for f in sys.meta_path if "Redirecting" not in type(f).__name__]
        sys.path.insert(0, os.environ["OSTEON_OTHER_BUILD"])
    import osteon

    d = np.load(path)
    kw = ast.literal_eval(str(d["kw"]))   # the Analyzer's keywords: numbers, lists, None
    w = sp.csr_matrix((d["w_data"], d["w_indices"], d["w_indptr"]), shape=tuple(d["w_shape"]))
    names = [str(n) for n in d["names"]] or None

    def skeleton(i):
        return osteon.Skeleton(d["heads"][i], d["tails"][i], d["parents"], names=names)

    return osteon, d, kw, w, skeleton


def replay(path: str, runs: int, threads: int | None, fresh: bool = False) -> list:
    """The captured updates: the Analyzer built as Live built it, then `runs` runs (the first
    full, then the captured updates in turn); returns the results. `fresh`: each update by an
    Analyzer of its own (a one-off analysis: what a reused one must give, bit for bit)."""
    osteon, d, kw, w, skeleton = _load(path)
    if threads is not None:
        kw["threads"] = threads
    an = osteon.Analyzer(d["faces"], int(d["nv"]), skeleton(0), w, **kw)
    n = len(d["vertices"])
    out = []
    for r in range(runs):
        i = r % n
        if fresh:
            an = osteon.Analyzer(d["faces"], int(d["nv"]), skeleton(i), w, **kw)
        out.append(an.run(d["vertices"][i], skeleton(i)))
    return out


def instructions(path: str, runs: int, keep: str | None = None) -> None:
    """callgrind of the engine's runs, one thread: 1, 2 and `runs` runs. The first update
    (2 runs - 1 run) also fills what later updates reuse; an update after it is
    (`runs` runs - 2 runs) / (`runs` - 2). Stages by inclusive counts of their functions."""
    totals, stages = {}, {}
    counts = (1, 2, runs)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = keep or tmp
        os.makedirs(tmp, exist_ok=True)
        for n in counts:
            out = os.path.join(tmp, f"cg.{n}")
            subprocess.run(
                ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
                 "--toggle-collect=osteon::Analyzer::Impl::run*", sys.executable, __file__,
                 "--replay", path, "--runs", str(n), "--threads", "1", "--repeat", "1"],
                check=True, capture_output=True, text=True)
            with open(out) as fh:
                totals[n] = next(int(line.split()[1]) for line in fh if line.startswith("totals:"))
            ann = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", out],
                                 check=True, capture_output=True, text=True).stdout
            stages[n] = _stage_counts(ann)
    steady = (totals[runs] - totals[2]) / (runs - 2)
    print(f"engine instructions per live update: {steady / 1e6:.1f} M (({runs} runs - 2 runs) / "
          f"{runs - 2}); the first update {(totals[2] - totals[1]) / 1e6:.1f} M, the first "
          f"(full) run {totals[1] / 1e6:.1f} M")
    print("| function (inclusive) | M instructions per update | first update |")
    print("|---|---|---|")
    for k in stages[runs]:
        v = (stages[runs][k] - stages[2].get(k, 0)) / (runs - 2)
        first = stages[2].get(k, 0) - stages[1].get(k, 0)
        print(f"| {k} | {v / 1e6:.1f} | {first / 1e6:.1f} |")


def _stage_counts(annotate: str) -> dict:
    """Inclusive instruction counts of the functions whose name starts with one of
    REPLAY_STAGES (the largest entry per stage)."""
    found = {}
    for line in annotate.splitlines():
        parts = line.strip().split(None, 2)
        if len(parts) < 2:
            continue
        try:
            count = int(parts[0].replace(",", ""))
        except ValueError:
            continue
        fn = parts[-1].split(":", 1)[-1].split(" [", 1)[0]
        for st in REPLAY_STAGES:
            if fn.startswith((st + "(", st + "::")) or fn == st:
                found[st] = max(found.get(st, 0), count)
    return found


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
    ap.add_argument("--pose", choices=("scale", "bend"), default="scale",
                    help="what changes per round: forearm.L's scale across its axis (default) "
                         "or its rotation (the elbow bends)")
    ap.add_argument("--capture", metavar="FILE", help="save the engine's inputs (.npz)")
    ap.add_argument("--profile", metavar="FILE",
                    help="cProfile of the timed updates into FILE (pstats; the table of the 40 "
                         "largest own times is printed; the per-part clocks are off)")
    ap.add_argument("--replay", metavar="FILE", help="re-run captured inputs without bpy")
    ap.add_argument("--runs", type=int, default=4, help="--replay: analyser runs")
    ap.add_argument("--threads", type=int, default=None, help="--replay: engine threads")
    ap.add_argument("--dump", metavar="FILE",
                    help="--replay: every number of every run's result into FILE (.npz), to "
                         "compare two builds bit for bit (bench/identity_dump.py compare)")
    ap.add_argument("--fresh", action="store_true",
                    help="--replay --dump: each update by a new Analyzer (a fresh analysis), to "
                         "compare with the reused one's dump bit for bit")
    ap.add_argument("--keep", metavar="DIR", help="--instructions: keep callgrind's files here")
    ap.add_argument("--instructions", action="store_true",
                    help="--replay under callgrind: instructions per update")
    args = ap.parse_args(argv)
    if args.replay and args.instructions:
        instructions(args.replay, max(3, args.runs), args.keep)
        return 0
    if args.replay and args.dump:
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        from identity_dump import _flatten

        out: dict = {}
        for i, a in enumerate(replay(args.replay, args.runs, args.threads, args.fresh)):
            a.section_thickness  # noqa: B018 -- the deferred thickness, as a report reads it
            _flatten(f"run{i}", a, out)
        np.savez(args.dump, **out)
        print(f"{len(out)} arrays of {args.runs} runs saved to {args.dump}")
        return 0
    if args.replay:
        t = []
        for _ in range(args.repeat):
            c0 = time.process_time()
            replay(args.replay, args.runs, args.threads)
            t.append(time.process_time() - c0)
        print(f"replay of {args.runs} runs: CPU {min(t) * 1e3:.1f} ms "
              f"(fastest of {args.repeat})")
        return 0
    return main_blender(args)


if __name__ == "__main__":
    if "--" in sys.argv:
        argv = sys.argv[sys.argv.index("--") + 1:]
    else:                       # inside Blender the other arguments are Blender's
        argv = [] if "bpy" in sys.modules else sys.argv[1:]
    code = main(argv)
    bpy = sys.modules.get("bpy")
    if bpy is not None and not bpy.app.binary_path:   # the bpy wheel: unregister or it hangs
        import osteon_blender

        osteon_blender.unregister()
    sys.exit(code)
