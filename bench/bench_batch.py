"""Batch throughput: models per second on 1 process, the process pool on all cores and a local
Dask cluster, over a generated library of a few hundred models, and where the time goes.

The library is made in a temporary folder from the models of tests/data (or OSTEON_DATA, e.g.
../shared/data for the RigNet set): the libigl / Hyperspectral TGF rigs (arm, elephant, cow, cheburashka, wolf,
cylinder) scaled, posed (a subtree of bones turned about its joint by linear blend skinning) and
subdivided (1-to-4, weights interpolated), written as OBJ + TGF + binary DMAT; the RigNet models
as they are (OBJ + _rig.txt; most are open meshes, so they fail as open on purpose); unrigged
copies (OBJ without a skeleton: skipped until auto_skeleton exists); the Fox glTF; and broken
files (garbage bytes, truncated OBJ).

    python bench/bench_batch.py [--models 240] [--jobs N] [--no-dask] [--png-sample 12]
        [--repeat 3] [--write] [--keep DIR]

Reported: models/s for each runner; the per-task split (read, check, analysis, picture) summed
over the models; and the analysis-only rate (osteon.analyze on the same models already in
memory, same process), which is the ceiling a runner could reach if reading were free. With
``--repeat N`` the runners alternate N times and the table shows medians; the CPU seconds
(user + system of this process and of every worker: a pool's fork server is stopped after each
run so that it and its workers are counted) tell the cost apart from the machine's load.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from models import DATA, subdivide

TGF_MODELS = {
    "arm": ("libigl-tutorial-data/arm.obj", "libigl-tutorial-data/arm.tgf",
            "libigl-tutorial-data/arm-weights.dmat"),
    "elephant": ("libigl-tutorial-data/elephant.obj", "libigl-tutorial-data/elephant.tgf",
                 "libigl-tutorial-data/elephant-weights.dmat"),
    "cow": ("Hyperspectral-Inverse-Skinning/cow_clean.obj", "Hyperspectral-Inverse-Skinning/cow.tgf",
            "Hyperspectral-Inverse-Skinning/cow.DMAT"),
    "cheburashka": ("Hyperspectral-Inverse-Skinning/cheburashka.obj",
                    "Hyperspectral-Inverse-Skinning/cheburashka.tgf",
                    "Hyperspectral-Inverse-Skinning/cheburashka.DMAT"),
    "wolf": ("Hyperspectral-Inverse-Skinning/wolf_clean.obj",
             "Hyperspectral-Inverse-Skinning/wolf.tgf", "Hyperspectral-Inverse-Skinning/wolf.DMAT"),
}


def _find(rel):
    p = DATA / rel
    if p.exists():
        return p
    for cand in p.parent.glob("*"):  # weights file names differ between datasets
        if cand.name.lower() == p.name.lower():
            return cand
    return None


def _rotation(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def _pose(V, joints, E, parents, W, rng):
    """Turn the subtree of one bone (not a root) about its head joint by 20-50 degrees (LBS)."""
    B = len(parents)
    cands = [b for b in range(B) if parents[b] >= 0] or list(range(B))
    b = int(rng.choice(cands))
    sub = {b}
    changed = True
    while changed:
        changed = False
        for k in range(B):
            if parents[k] in sub and k not in sub:
                sub.add(k)
                changed = True
    h = joints[E[b, 0]]
    R = _rotation(rng.normal(size=3), np.radians(rng.uniform(20, 50)))
    w = np.asarray(W[:, sorted(sub)].sum(axis=1)).ravel()
    d = V - h
    Vp = V + w[:, None] * (d @ R.T - d)
    J = joints.copy()
    moved = {int(E[k, 1]) for k in sub}
    for j in moved:
        J[j] = h + R @ (joints[j] - h)
    return Vp, J


def make_library(root: Path, n_models: int, seed: int = 0, unrigged: bool = True) -> dict:
    """Write about ``n_models`` models into ``root``; returns counts per kind."""
    from osteon.io import read_dmat, read_mesh, read_tgf, write_dmat, write_mesh, write_tgf

    rng = np.random.default_rng(seed)
    root.mkdir(parents=True, exist_ok=True)
    bases = []
    for name, (m, t, w) in TGF_MODELS.items():
        pm, pt, pw = _find(m), _find(t), _find(w)
        if pm and pt and pw:
            V, F = read_mesh(pm)
            joints, E, _, _, parents = read_tgf(pt)
            W = read_dmat(pw)
            if W.shape == (len(V), len(parents)):
                bases.append((name, V, F, joints, E, parents, W))
    rignet = sorted((DATA / "RigNet").glob("*_ori.obj")) if (DATA / "RigNet").is_dir() else []
    fox = DATA / "glTF-Sample-Models/Fox.glb"
    kinds = {"tgf variant": 0, "subdivided": 0, "rignet as is": 0, "unrigged": 0, "gltf": 0,
             "garbage": 0, "truncated": 0}
    plan = []
    # about: 55 % TGF variants, 8 % subdivided, 15 % RigNet, 10 % unrigged, rest gltf/broken
    n_var = int(0.55 * n_models)
    n_sub = max(1, int(0.08 * n_models))
    n_rig = min(int(0.15 * n_models), 3 * len(rignet)) if rignet else 0
    n_unr = int(0.10 * n_models) if unrigged else 0  # auto_skeleton: seconds per model
    n_bad = max(2, n_models - n_var - n_sub - n_rig - n_unr - 2)
    plan += ["var"] * n_var + ["sub"] * n_sub + ["rig"] * n_rig + ["unr"] * n_unr
    plan += ["gltf"] * (2 if fox.exists() else 0) + ["bad"] * n_bad
    for i, kind in enumerate(plan):
        d = root / f"g{i // 50:02d}"
        d.mkdir(exist_ok=True)
        stem = f"m{i:04d}"
        if kind in ("var", "sub", "unr") and bases:
            name, V, F, joints, E, parents, W = bases[i % len(bases)]
            s = float(rng.uniform(0.5, 3.0))  # file units differ; the print size is fixed
            Vs, Js = V * s, joints * s
            if kind != "unr" and rng.random() < 0.6:
                Vs, Js = _pose(Vs, Js, E, parents, W, rng)
            Fs, Ws = F, W
            if kind == "sub":
                import scipy.sparse as sp

                Vs, Fs, Wsp = subdivide(Vs, F, sp.csr_matrix(W))
                Ws = Wsp.toarray()
                kinds["subdivided"] += 1
            elif kind == "var":
                kinds["tgf variant"] += 1
            else:
                kinds["unrigged"] += 1
            write_mesh(d / f"{stem}_{name}.obj", Vs, Fs)
            if kind != "unr":
                write_tgf(d / f"{stem}_{name}.tgf", Js, E)
                write_dmat(d / f"{stem}_{name}.dmat", Ws, binary=True)
        elif kind == "rig" and rignet:
            src = rignet[i % len(rignet)]
            shutil.copy(src, d / f"{stem}_{src.name}")
            shutil.copy(src.with_name(src.stem + "_rig.txt"), d / f"{stem}_{src.stem}_rig.txt")
            kinds["rignet as is"] += 1
        elif kind == "gltf":
            shutil.copy(fox, d / f"{stem}_Fox.glb")
            kinds["gltf"] += 1
        else:
            if i % 2:
                (d / f"{stem}_garbage.stl").write_bytes(rng.bytes(4096))
                kinds["garbage"] += 1
            else:
                V, F = (bases[0][1], bases[0][2]) if bases else (np.eye(3), np.array([[0, 1, 2]]))
                write_mesh(d / f"{stem}_cut.obj", V, F)
                text = (d / f"{stem}_cut.obj").read_text()
                (d / f"{stem}_cut.obj").write_text(text[: len(text) // 3] + "f 1 2 99999999\n")
                if bases:
                    write_tgf(d / f"{stem}_cut.tgf", bases[0][3], bases[0][4])
                kinds["truncated"] += 1
    return kinds


def _cpu_seconds() -> float:
    """CPU seconds (user + system) of this process and of its children that have ended."""
    import resource

    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def _stop_forkserver():
    """End the pool's fork server (if one was started), so that its CPU time and its workers'
    are counted, and the next run starts it again as a new ``osteon batch`` would."""
    import multiprocessing.forkserver as fs

    stop = getattr(fs._forkserver, "_stop", None)
    if stop is not None:
        stop()


def timed_run(lib, settings, **kw):
    """(wall s, CPU s of this process and every worker, records) of one ``batch.run``."""
    from osteon import batch

    cpu = _cpu_seconds()
    t = time.perf_counter()
    recs = list(batch.run([lib], settings, **kw))
    wall = time.perf_counter() - t
    _stop_forkserver()
    return wall, _cpu_seconds() - cpu, recs


def analysis_only_rate(lib, settings, repeat=3):
    """osteon.analyze on every analysable model already loaded (no reading), same settings."""
    import osteon
    from osteon import batch
    from osteon.batch.task import _load

    s = batch.BatchSettings.from_any(settings)
    models = []
    for m in batch.discover([lib]):
        try:
            mod = _load(Path(m.path), s)
        except Exception:  # noqa: BLE001, S112 - bad files are part of the library
            continue
        if batch.mesh_boundary(mod.faces, len(mod.vertices))[0] == 0:
            models.append(mod)
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        for mod in models:
            osteon.analyze(mod.vertices, mod.faces, mod.skeleton, mod.weights,
                           **s.engine_kwargs(mod.bone_names))
        times.append(time.perf_counter() - t)
    return len(models), statistics.median(times)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--models", type=int, default=240)
    ap.add_argument("--jobs", type=int, default=os.cpu_count())
    ap.add_argument("--no-dask", action="store_true")
    ap.add_argument("--png-sample", type=int, default=12,
                    help="models run with pictures on 1 process to time the picture (0: skip)")
    ap.add_argument("--keep", metavar="DIR", help="make the library here and keep it "
                    "(an existing DIR/lib is used as it is)")
    ap.add_argument("--write", action="store_true",
                    help="also time runs that write an output folder (as osteon batch --out)")
    ap.add_argument("--repeat", type=int, default=1, metavar="N",
                    help="runs of each runner, alternating (the table shows medians)")
    ap.add_argument("--no-unrigged", action="store_true",
                    help="no unrigged models (their auto_skeleton, seconds each, is not reading)")
    args = ap.parse_args(argv)
    import osteon

    tmp = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="osteon-batch-"))
    lib = tmp / "lib"
    t = time.perf_counter()
    if args.keep and lib.is_dir():
        from osteon import batch

        kinds = {"existing": len(batch.discover([lib]))}
    else:
        kinds = make_library(lib, args.models, unrigged=not args.no_unrigged)
    gen = time.perf_counter() - t
    n_files = sum(kinds.values())
    print(f"osteon {osteon.__version__}; {os.cpu_count()} cores; library of {n_files} models "
          f"made in {gen:.1f} s in {lib}: " + ", ".join(f"{v} {k}" for k, v in kinds.items() if v))
    settings = {"force_n": 20.0, "material": "PLA", "png": False}
    rows = []
    runs: dict = {"1 process": [], f"pool, {args.jobs} processes": []}
    if args.write:
        runs.update({"1 process, --out": [], f"pool, {args.jobs} processes, --out": []})
    # "1 process": in this process (no time limit; with one, -j 1 runs in one worker process)
    one = {**settings, "model_timeout_s": 0}
    for k in range(args.repeat):  # alternating, so that all see the same machine load
        runs["1 process"].append(timed_run(lib, one, workers=1))
        runs[f"pool, {args.jobs} processes"].append(timed_run(lib, settings, workers=args.jobs))
        if args.write:  # the CLI's path: a JSON report per model, results.jsonl, summaries
            runs["1 process, --out"].append(
                timed_run(lib, one, workers=1, out=tmp / f"out1_{k}"))
            runs[f"pool, {args.jobs} processes, --out"].append(
                timed_run(lib, settings, workers=args.jobs, out=tmp / f"outp_{k}"))
    for name, rr in runs.items():
        wall = statistics.median(r[0] for r in rr)
        cpu = statistics.median(r[1] for r in rr)
        rows.append((name, wall, rr[-1][2], cpu))
    secs1, recs = rows[0][1], rows[0][2]
    if not args.no_dask:
        try:
            import distributed
        except ImportError:
            distributed = None
            print("distributed not installed: Dask row skipped")
        if distributed is not None:
            t = time.perf_counter()
            with distributed.LocalCluster(n_workers=args.jobs, threads_per_worker=1,
                                          processes=True, dashboard_address=None) as cl, \
                    distributed.Client(cl) as client:
                client.run(lambda: __import__("osteon.batch._warm"))  # as the pool's server
                start = time.perf_counter() - t
                secsd, _, recsd = timed_run(lib, settings, client=client)
            rows.append((f"Dask LocalCluster, {args.jobs} workers (+{start:.1f} s start)",
                         secsd, recsd, None))
    n_ok, secs_a = analysis_only_rate(lib, settings)
    rate_a = n_ok / secs_a
    statuses = {}
    for r in recs:
        statuses[r["status"]] = statuses.get(r["status"], 0) + 1
    print("statuses: " + ", ".join(f"{v} {k}" for k, v in statuses.items()))
    reasons = {}
    for r in recs:
        if r["reason"]:
            key = r["reason"].split(":")[0][:40]
            reasons[key] = reasons.get(key, 0) + 1
    print("reasons: " + ", ".join(f"{v} {k}" for k, v in sorted(reasons.items(), key=lambda x: -x[1])))
    ok = [r for r in recs if r["status"] == "ok"]
    same = all(
        {r["model"]: r.get("max_stress_mpa") for r in rr} == {r["model"]: r.get("max_stress_mpa")
                                                              for r in recs}
        for _, _, rr, _ in rows
    )
    print(f"every runner gives the same max stress per model: {same}")
    print()
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; medians of "
          f"{args.repeat} alternating runs; CPU s: this process and every worker")
    print("| runner | models | wall s | models/s | analysed/s | vs analysis-only | CPU s | "
          "CPU ms/model |")
    print("|---|---|---|---|---|---|---|---|")
    for name, secs, rr, cpu in rows:
        n_an = sum(r["status"] == "ok" for r in rr)
        cpu_text = "-" if cpu is None else f"{cpu:.2f} | {1000 * cpu / len(rr):.1f}"
        print(f"| {name} | {len(rr)} | {secs:.2f} | {len(rr) / secs:.1f} | {n_an / secs:.1f} | "
              f"{(n_an / secs) / rate_a:.3f} | {cpu_text} |")
    print(f"| analysis only (models in memory, 1 thread) | {n_ok} | {secs_a:.2f} | - | "
          f"{rate_a:.1f} | 1 | - | - |")
    print()
    tot = {k: sum(r.get(k, 0.0) for r in recs) for k in
           ("read_seconds", "check_seconds", "analysis_seconds", "png_seconds", "seconds")}
    other = tot["seconds"] - sum(v for k, v in tot.items() if k != "seconds")
    print("where the time of the 1-process run goes (sum over tasks):")
    for k in ("read_seconds", "check_seconds", "analysis_seconds"):
        print(f"  {k[:-8]:<9} {tot[k]:7.2f} s  {100 * tot[k] / tot['seconds']:5.1f} %")
    print(f"  other     {other:7.2f} s  {100 * other / tot['seconds']:5.1f} %  (report, errors)")
    print(f"  runner overhead (wall - tasks): {secs1 - tot['seconds']:.2f} s")
    if ok:
        faces = np.array([r["faces"] for r in ok])
        print(f"analysed models: {len(ok)}, faces median {int(np.median(faces))}, max {faces.max()}")
    if args.png_sample:
        from osteon import batch

        sample = [Path(r["model"]) for r in ok[: args.png_sample]]
        out = tmp / "png_out"
        t = time.perf_counter()
        pr = list(batch.run(sample, {**one, "png": True}, workers=1, out=out))
        wall = time.perf_counter() - t
        png = [r["png_seconds"] for r in pr if r["status"] == "ok"]
        print(f"with pictures (1 process, {len(pr)} models): {len(pr) / wall:.1f} models/s; "
              f"picture median {1000 * statistics.median(png):.0f} ms per model")
    if not args.keep:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
