"""How stable is the corner reading under a tiny change of the mesh? (issue 33, docs/notch.md
"Round 7: Stability of the reading").

    python scripts/study_notch_stability.py INPUTS.pkl --build main=/tmp/main_build \\
        --build r7=/tmp/r7_build [--runs 20] [--out /tmp/stab.json]

INPUTS.pkl: the sample figurine as the Blender add-on analyses it, a tuple (mesh, params, W):
mesh a dict with ``v`` (mm), ``f``, ``heads``, ``tails`` (Blender units, as the add-on's
``inputs.skeleton``), ``parents``, ``names``; ``params`` the add-on's engine keywords; ``W``
the (V, B) CSR weights. The add-on scales the skeleton by its mm per Blender unit
(service.engine_skeleton); the dump does not hold it, so it is recovered from the weights (the
sample's distance weights, blender_addon/osteon_blender/sample.py, reproduced to 3e-6).
Made in the bpy wheel's venv (scripts/blender_setup.sh) with::

    .venv-bpy/bin/python - <<'PY'
    import pickle, sys, numpy as np
    sys.path[:0] = ["blender_addon", "tests/blender"]
    import bpy, osteon_blender
    from conftest import empty_scene
    from osteon_blender import sample, service
    osteon_blender.register(); empty_scene(); obj, arm = sample.build()
    bpy.context.view_layer.objects.active = obj
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    inp = service.LAST[bpy.context.scene.name]["inputs"]; sk = inp.skeleton
    mesh = dict(v=np.asarray(inp.vertices_mm), f=np.asarray(inp.faces), heads=np.asarray(sk.heads),
                tails=np.asarray(sk.tails), parents=np.asarray(sk.parents), names=list(sk.names))
    pickle.dump((mesh, inp.params, inp.weights), open("/tmp/sample_inputs.pkl", "wb"))
    PY

Each build (a directory holding an ``osteon`` package) runs in its own child process (two
pybind11 builds cannot share one; bench/compare_builds.py's OTHER_BUILD_IMPORT). Each child
corrects the sample under its own rule (``osteon.correct`` with the add-on's keywords: max
scale 3, 100 rounds, thin scaling, the bones' roll-0 X axes), then every build analyses: the
sample, each build's corrected mesh, each perturbed ``--runs`` times by uniform noise of
±1e-4 and ±1e-6 × the model's size on every coordinate (fixed seeds, the same noise for both
builds) and once rounded to float32 (as Blender holds it), and the sample mirrored in x (faces
flipped). Prints per corner section (Kt > 1 in any
run) Kt min/median/max, radius min/max, the opening factor inferred from Kt (step D/d from the
engine, d from the section's equivalent radius: approximate), and how many sections' governing
stress moves by more than 5 % in any run.
"""

from __future__ import annotations

import argparse
import json
import os
import pickle
import subprocess
import sys
import types
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
LEVELS = (1e-4, 1e-6)

CHILD = """
import os, sys
sys.meta_path = [f for f in sys.meta_path if "Redirecting" not in type(f).__name__]
sys.path.insert(0, os.environ["OSTEON_OTHER_BUILD"])
sys.path.insert(0, {here!r})
import study_notch_stability as s
s.child({stage!r}, {inputs!r}, {meshes!r}, {runs}, {out!r})
"""


def mm_per_unit(mesh: dict, w) -> float:
    """The add-on's mm per Blender unit: the k whose sample distance weights of v / k match W."""
    from scipy.optimize import minimize_scalar

    sys.modules.setdefault("bpy", types.ModuleType("bpy"))
    sys.path.insert(0, str(ROOT / "blender_addon" / "osteon_blender"))
    import sample

    segs = [(np.array(sample.JOINTS[h][0]), np.array(sample.JOINTS[t][0]))
            for h, t, _p in sample.BONES.values()]
    wd = w.toarray()
    v = np.asarray(mesh["v"], float)
    err = lambda k: np.abs(sample.distance_weights(v / k, segs) - wd).max()
    k0 = float(np.ptp(v[:, 2]) / 2.35)  # the sample's height, ~2.35 units
    r = minimize_scalar(err, bounds=(0.9 * k0, 1.1 * k0), method="bounded",
                        options={"xatol": 1e-12})
    if r.fun > 1e-5:
        raise SystemExit(f"weights not reproduced (max error {r.fun:.2g}): not the sample?")
    return float(r.x)


def roll0_x_axes(heads: np.ndarray, tails: np.ndarray) -> np.ndarray:
    """Blender's X axis of a bone of roll 0 (vec_roll_to_mat3: the shortest rotation taking Y
    to the bone's axis)."""
    n = tails - heads
    n = n / np.linalg.norm(n, axis=1, keepdims=True)
    x, y, z = n.T
    th = 1.0 + y
    return np.stack([1.0 - x * x / th, -x, -x * z / th], axis=1)


def load(inputs: str):
    with open(inputs, "rb") as fh:
        mesh, params, w = pickle.load(fh)
    k = mesh.get("k") or mm_per_unit(mesh, w)
    heads, tails = np.asarray(mesh["heads"]) * k, np.asarray(mesh["tails"]) * k
    return mesh, params, w, heads, tails


def child(stage: str, inputs: str, meshes: list, runs: int, out: str) -> None:
    import osteon

    mesh, params, w, heads, tails = load(inputs)
    v0, f = np.asarray(mesh["v"], float), np.asarray(mesh["f"])
    sk = osteon.Skeleton(heads, tails, mesh["parents"], names=list(mesh["names"]))
    if stage == "correct":
        fix = osteon.correct(v0, f, sk, w, bone_x_axes=roll0_x_axes(heads, tails),
                             max_scale=3.0, max_rounds=100, scaling="thin", **params)
        np.savez(out, v=np.asarray(fix.vertices), scale_x=np.asarray(fix.bone_scale_x),
                 scale_z=np.asarray(fix.bone_scale_z), build=osteon.__file__)
        return
    size = float(np.ptp(v0, axis=0).max())
    res = {}

    def run(tag, v, faces=f, skel=sk):
        a = osteon.analyze(v, faces, skel, w, **params)
        res[tag] = np.stack([np.nan_to_num(np.asarray(x, float), nan=0.0) for x in (
            a.stress_concentration, a.notch_radius, a.notch_step, a.stress,
            a.section_area, a.section_bone)])

    for name, path in meshes:
        v = v0 if path is None else np.load(path)["v"]
        run(f"{name}/0", v)
        run(f"{name}/f32", v.astype(np.float32).astype(float))  # as Blender holds it
        for lvl in LEVELS:
            for i in range(runs):
                rng = np.random.default_rng(1000 * i + int(-np.log10(lvl)))
                run(f"{name}/{lvl:g}/{i}", v + rng.uniform(-lvl * size, lvl * size, v.shape))
    m = v0 * [-1.0, 1.0, 1.0]
    hm, tm = heads * [-1.0, 1.0, 1.0], tails * [-1.0, 1.0, 1.0]
    run("mirror", m, f[:, ::-1].copy(),
        osteon.Skeleton(hm, tm, mesh["parents"], names=list(mesh["names"])))
    np.savez(out, build=osteon.__file__, **res)


def spawn(build: str, stage: str, inputs: str, meshes: list, runs: int, out: str) -> None:
    code = CHILD.format(here=str(Path(__file__).resolve().parent), stage=stage, inputs=inputs,
                        meshes=meshes, runs=runs, out=out)
    env = dict(os.environ, OSTEON_OTHER_BUILD=build)
    subprocess.run([sys.executable, "-c", code], env=env, check=True)
    got = str(np.load(out)["build"])
    if not got.startswith(build):
        raise SystemExit(f"{build}: imported {got} instead")


def acute_factor_of(kt, radius, step, area, osteon) -> float:
    """(Kt - 1) over the stepped bar's (D/d = step, d from the section's area): ~1 shoulder."""
    d = 2.0 * np.sqrt(area / np.pi)
    base = osteon.shoulder_fillet_kt(step * d, d, radius)
    return (kt - 1.0) / (base - 1.0) if base > 1.0 else float("nan")


def table(res: dict, prefix: str, lvl: float, names, osteon) -> tuple[list, int]:
    base = res[f"{prefix}/0"]
    runs = np.stack([res[k] for k in res if k.startswith(f"{prefix}/{lvl:g}/")])
    kt, rad, step, stress, area = (runs[:, j] for j in range(5))
    bones = base[5].astype(int)
    f32 = res[f"{prefix}/f32"]
    corner = np.flatnonzero((kt > 1).any(axis=0) | (base[0] > 1) | (f32[0] > 1))
    rows = []
    for s in corner:
        ks = kt[:, s]
        rs = rad[:, s][ks > 1]
        fac = [acute_factor_of(k, r, st, a, osteon) for k, r, st, a
               in zip(ks, rad[:, s], step[:, s], area[:, s]) if k > 1]
        rows.append({
            "section": f"{names[bones[s]]} s{s}", "kt0": round(float(base[0, s]), 3),
            "kt_min": round(float(ks.min()), 3), "kt_med": round(float(np.median(ks)), 3),
            "kt_max": round(float(ks.max()), 3),
            "r_min": round(float(rs.min()), 3) if len(rs) else None,
            "r_max": round(float(rs.max()), 3) if len(rs) else None,
            "factor": [round(float(np.nanmin(fac)), 2), round(float(np.nanmax(fac)), 2)]
            if fac else None,
            "stress_move": round(float(np.abs(stress[:, s] / base[3, s] - 1).max()), 4)
            if base[3, s] > 0 else None,
            "runs_off_5pct": int((np.abs(ks - base[0, s]) > 0.05 * base[0, s]).sum()),
            "f32": [round(float(f32[0, s]), 3), round(float(f32[1, s]), 3)]})
    moved = np.flatnonzero((np.abs(stress / np.where(base[3] > 0, base[3], 1) - 1) > 0.05)
                           .any(axis=0))
    return rows, [f"{names[bones[s]]} s{s}" for s in moved]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("inputs")
    ap.add_argument("--build", action="append", required=True, help="NAME=DIR")
    ap.add_argument("--runs", type=int, default=20)
    ap.add_argument("--work", default="/tmp/stab_work")
    ap.add_argument("--out", default="/tmp/stab.json")
    a = ap.parse_args()
    builds = dict(b.split("=", 1) for b in a.build)
    work = Path(a.work)
    work.mkdir(exist_ok=True)
    meshes = [("sample", None)]
    for name, b in builds.items():
        p = work / f"corrected_{name}.npz"
        if not p.exists():
            spawn(b, "correct", a.inputs, [], 0, str(p))
        z = np.load(p)
        print(f"corrected under {name}: scale x {np.round(z['scale_x'], 3).tolist()}",
              flush=True)
        meshes.append((f"corrected_{name}", str(p)))
    results = {}
    for name, b in builds.items():
        p = work / f"analyses_{name}.npz"
        if not p.exists():
            spawn(b, "analyze", a.inputs, meshes, a.runs, str(p))
        results[name] = dict(np.load(p))
    sys.path.insert(0, next(iter(builds.values())))
    import osteon  # only for shoulder_fillet_kt (the same fit in both builds)

    with open(a.inputs, "rb") as fh:
        mesh = pickle.load(fh)[0]
    names = list(mesh["names"])
    report = {}
    for rule, res in results.items():
        for mname, _p in meshes:
            for lvl in LEVELS:
                rows, moved = table(res, mname, lvl, names, osteon)
                report[f"{rule} {mname} {lvl:g}"] = {"rows": rows, "stress_moved_5pct": moved}
                print(f"\n== rule {rule}, mesh {mname}, noise ±{lvl:g} × size: "
                      f"{len(moved)} sections' stress moves > 5 %: {', '.join(moved)}")
                for r in rows:
                    print("  " + json.dumps(r))
        base, mir = res["sample/0"], res["mirror"]
        bones = base[5].astype(int)
        pairs = np.flatnonzero((base[0] > 1) | (mir[0] > 1))
        report[f"{rule} mirror"] = [
            {"section": f"{names[bones[s]]} s{s}", "kt": [round(float(base[0, s]), 3),
                 round(float(mir[0, s]), 3)], "r": [round(float(base[1, s]), 3),
                 round(float(mir[1, s]), 3)]} for s in pairs]
        print(f"\n== rule {rule}, mirrored in x (as built -> mirrored):")
        for r in report[f"{rule} mirror"]:
            print("  " + json.dumps(r))
    Path(a.out).write_text(json.dumps(report, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
