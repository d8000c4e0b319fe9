"""Issue 33's second "Show" item: docs/validation.md's per-section and junction rows re-measured
with the corner model, FEM read on the plane and by the corner (``osteon.fem.peaks``).

Two steps, run separately, so that the table can be re-printed without FEM:

    nice -n 10 .venv/bin/python scripts/fem_corners.py fem [--model NAME] [--fine 6] [--only S]
    .venv/bin/python scripts/fem_corners.py table

The FEM step runs ``osteon validate MODEL --fem --section S`` 's pipeline (crop mode, the
defaults: F = 20 N, 120 mm, h = 2 mm, PLA, elements r/3 near the section; ``--fine 6``: r/6, the
convergence check) on each section of ROWS not yet cached and stores the report's row in
``scripts/fem_corners.json`` (per model, section and fine factor). The rig (bench/make_junction_rig.py,
needs manifold3d) is built into --rig DIR.

The comparison (defined and committed before the first FEM run on these models; the FEM
neighbourhood is ``osteon.fem.peaks``'s docstring):
* FEM on the plane: the worst σ_nn on the section's plane (what ``validate --fem`` read before).
* FEM by the corner: the largest principal stress, worst force direction, over the slab between
  the section's two neighbour planes (±h), its connected piece, away from the load point (r) and
  the clamp (2 r).
* osteon's claim in that slab: the largest governing stress of the same bone's sections whose
  centres lie within h (+1 µm) of the plane along its normal (the section and its neighbours;
  and, a fix made after the first table was printed, within 2 r of its centre across the normal:
  a bone's sections elsewhere, e.g. the rig's s105 on bone_3, are not neighbours):
  a corner between two planes is claimed by the section on its thin side, which may be the
  neighbour. ratio = claim / FEM by the corner.
* the corner's radius on the mesh: the radius osteon measures with ``min_notch_radius`` 0.01 mm
  (the print clamp off): 0.01 = a sharp crease (FEM's peak there does not converge: it grows as
  the mesh is refined); larger = a finite radius. For a section without a corner in its slab:
  none.
* the verdict (issue 33): a row whose claimed corner has a finite radius fails when ratio < 0.85.
  (Added after the first four rows were read, and said so in docs/validation.md: a section with
  a finite corner of its own is judged by its own governing stress against FEM by the corner,
  not by a neighbour's larger claim, when that neighbour's corner is a crease; the fish's tail
  stem s62 has its own 2.48 mm corner, its neighbour s63 a crease.)
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data"
CACHE = Path(__file__).with_name("fem_corners.json")
#: FEM's corner peak counts as converged when r/3 -> r/6 changes it by at most this (judgement,
#: set after the first refinements were read: the studies' smooth fillets moved 1-3 %; the
#: tested creases here 12-49 %)
CONVERGED = 0.10
HIS = "Hyperspectral-Inverse-Skinning/"
MODELS = {  # name: validate's arguments (docs/validation.md's commands)
    "arm": ["libigl-tutorial-data/arm.obj"],
    "cow": [HIS + "cow_clean.obj", "--skeleton", HIS + "cow.tgf", "--weights", HIS + "cow.DMAT"],
    "cow_clean": [HIS + "cow_clean.obj", "--skeleton", HIS + "cow.tgf"],
    "dog": ["RigNet/2982_ori.obj", "--skeleton", "RigNet/2982_ori_rig.txt"],
    "fish": ["RigNet/11814_ori.obj", "--skeleton", "RigNet/11814_ori_rig.txt"],
    "elephant": ["libigl-tutorial-data/elephant.obj"],
    "cheburashka": [HIS + "cheburashka.obj"],
    "rig": ["RIG/junction_rig.obj", "--skeleton", "RIG/junction_rig.tgf", "--height-mm", "90"],
}
# (model, section, the docs' row): the sections of docs/validation.md's "Per section" table
# (found on today's build by bone and beam stress: the same planes) and its junction rows with a
# FEM number; the priority order of the brief
ROWS = [
    ("fish", 62, "per-section fish #3 (tail stem)"),
    ("dog", 104, "per-section dog #1"), ("dog", 114, "per-section dog #2"),
    ("dog", 45, "per-section dog #3"), ("dog", 63, "per-section dog #4"),
    ("dog", 57, "junction: elbow bulge"), ("dog", 39, "junction: elbow bulge"),
    ("dog", 97, "junction: knee bulge"), ("dog", 28, "junction: shoulder"),
    ("cheburashka", 24, "per-section cheburashka #1 (hand)"),
    ("cheburashka", 41, "per-section cheburashka #2 (hand)"),
    ("cheburashka", 20, "junction: forearm fused to the torso"),
    ("rig", 4, "junction: spine through the hips"), ("rig", 6, "junction: spine by the hips"),
    ("rig", 22, "junction: spine through the shoulders"), ("rig", 57, "junction: right leg's root"),
    ("rig", 81, "junction: right arm's root"), ("rig", 69, "junction: left arm's root"),
    ("rig", 14, "junction: spine through the fin stub"),
    ("fish", 67, "per-section fish #1"), ("fish", 38, "per-section fish #2"),
    ("fish", 51, "per-section fish #4"),
    ("elephant", 13, "per-section elephant #1"), ("elephant", 10, "junction: limb root"),
    ("arm", 51, "per-section arm #1"), ("arm", 31, "per-section arm #2"),
    ("arm", 56, "per-section arm #3"),
    ("cow", 192, "per-section cow #1"), ("cow", 177, "per-section cow #2"),
    ("cow", 157, "per-section cow #3"), ("cow", 86, "per-section cow #4"),
    ("cow_clean", 78, "junction: leg root"), ("cow_clean", 49, "junction: other leg"),
    ("cow_clean", 153, "junction: front leg root"), ("cow_clean", 173, "junction: its mirror"),
]


def argv_of(name, rig):
    out = []
    for a in MODELS[name]:
        if a.startswith("RIG/"):
            out.append(str(Path(rig) / a[4:]))
        elif a.endswith((".obj", ".tgf", ".txt", ".DMAT")):
            out.append(str(DATA / a))
        else:
            out.append(a)
    return out


def analysis_of(name, rig, min_notch_radius=None):
    from osteon.cli import common, parser

    extra = [] if min_notch_radius is None else ["--min-notch-radius", str(min_notch_radius)]
    args = parser.build_parser().parse_args(["validate", *argv_of(name, rig), "--fem", *extra])
    settings = common.settings_from_args(args)
    model = common.load_model_of(args)
    a, _ = common.run_analysis(settings, model)
    return model, a


def load_cache():
    return json.loads(CACHE.read_text()) if CACHE.exists() else {}


def save_cache(cache):
    CACHE.write_text(json.dumps(cache, indent=1, sort_keys=True) + "\n")


def key(name, index, fine):
    return f"{name} s{index} r/{fine:g}"


def commit():
    return subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                          capture_output=True, text=True, check=False).stdout.strip()


def run_fem(args):
    from osteon import fem

    if args.model is None or "rig" in args.model.split(","):
        rig = Path(args.rig)
        if not (rig / "junction_rig.obj").exists():
            subprocess.run([sys.executable, str(ROOT / "bench" / "make_junction_rig.py"),
                            str(rig)], check=True)
    models = {}
    for name, index, _ in ROWS:
        if args.model is not None and name not in args.model.split(","):
            continue
        if args.only is not None and index not in args.only:
            continue
        k = key(name, index, args.fine)
        if k in load_cache() and not args.again:
            continue
        if name not in models:
            models[name] = analysis_of(name, args.rig)
        model, a = models[name]
        sec = fem.chosen_sections(a, [index])
        t0 = time.time()
        rep = fem.cross_check(model.vertices, model.faces, sec, force=20.0,
                              hold_point=fem.hold_point(a, model.heads), threads=args.threads,
                              fine_factor=args.fine, mesh_timeout_s=args.timeout)
        row = ({"failed": rep.failed} if not rep.sections else rep.sections[0].as_dict())
        row.update(seconds=round(time.time() - t0, 1), commit=commit(), nodes_total=rep.nodes)
        cache = load_cache()
        cache[k] = row
        save_cache(cache)
        print(f"{k}: {'failed' if 'failed' in row else 'done'} in {row['seconds']} s",
              file=sys.stderr, flush=True)
    return 0


def slab_claim(a, i):
    """osteon's claim in section i's slab: (largest governing stress, its section) of the same
    bone's sections within h of i's plane (module docstring)."""
    bone = np.asarray(a.section_bone)
    c = np.asarray(a.section_center, float)
    n = np.asarray(a.section_normal[i], float)
    h = float(a.interval)
    same = np.nonzero(bone == bone[i])[0]
    d = c[same] - c[i]
    along = d @ n
    across = np.linalg.norm(d - np.outer(along, n), axis=1)
    r = np.sqrt(float(a.section_area[i]) / np.pi)
    near = same[(np.abs(along) <= h + 1e-3) & (across <= 2.0 * r)]
    near = near[np.isfinite(np.asarray(a.stress)[near])]
    j = int(near[np.argmax(np.asarray(a.stress)[near])])
    return float(a.stress[j]), j


def fmt(x, f="{:.2f}"):
    return "—" if x is None or not np.isfinite(x) else f.format(x)


def table(args):
    cache = load_cache()
    analyses = {}
    print("| model | row | section (bone) | nominal MPa | Kt | r mm (raw) | governing MPa | FEM "
          "plane MPa | governing / plane | FEM corner r/3 MPa (σ_nn; offset mm) | r/6 | governing / "
          "corner | claim in slab MPa (section: Kt, r mm (raw)) | claim / corner | corner |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    verdict = []
    for name, i, label in ROWS:
        row = cache.get(key(name, i, 3))
        if row is None:
            print(f"| {name} | {label} | s{i} | not run |")
            continue
        if name not in analyses:
            analyses[name] = (analysis_of(name, args.rig)[1],
                              analysis_of(name, args.rig, 0.01)[1])
        a, raw = analyses[name]
        bone = a.bone_names[int(a.section_bone[i])]
        if "failed" in row:
            why = row["failed"][0]["reason"].replace("|", " ").split(";")[0][:60]
            print(f"| {name} | {label} | s{i} ({bone}) | FEM failed: {why} |")
            continue
        claim, j = slab_claim(a, i)
        kt_j = float(a.stress_concentration[j])
        r_j, r_raw_j = float(a.notch_radius[j]), float(raw.notch_radius[j])
        corner = row["fem_corner_peak_mpa"]
        fine = cache.get(key(name, i, 6))
        fine_ok = fine is not None and "failed" not in fine
        ref = fine["fem_corner_peak_mpa"] if fine_ok else corner
        gov = float(a.stress[i])
        own = float(a.stress_concentration[i]) > 1.0
        own_finite = own and float(raw.notch_radius[i]) > 0.0101
        slab_finite = kt_j > 1.0 and r_raw_j > 0.0101
        # judged: a section with a finite corner of its own by its own governing stress; else,
        # one whose slab holds a neighbour's finite corner by the slab's claim
        if own_finite:
            status, ratio = "own, finite", gov / ref
        elif slab_finite:
            status, ratio = f"s{j}'s, finite", claim / ref
        elif own or kt_j > 1.0:
            status, ratio = "crease", None
        else:
            status, ratio = "none", None
        if row["fem_stress_mpa"] < 0.01 * gov:
            # the load point is not downstream of this section in the FEM model's sense: osteon's
            # farthest point lies off this limb, FEM finds the section unloaded (docs' cow s173)
            status, ratio = "FEM unloaded (the load point is off this limb)", None
        if fine_ok:
            grow = ref / corner - 1.0
            status += f"; FEM r/3 → r/6 {100 * grow:+.0f} %"
            if grow > CONVERGED and ratio is not None:
                # FEM's peak does not converge: a crease on the mesh, whatever osteon's fit reads
                status, ratio = status + ": not converged (a crease on the mesh)", None
        elif ratio is not None:
            status += "; not refined"
        print(f"| {name} | {label} | s{i} ({bone}) | {a.nominal_stress[i]:.2f} | "
              f"{a.stress_concentration[i]:.2f} | {fmt(a.notch_radius[i])} "
              f"({fmt(raw.notch_radius[i])}) | {gov:.2f} | {row['fem_stress_mpa']:.2f} | "
              f"{gov / row['fem_stress_mpa']:.2f} | {corner:.2f} "
              f"({row['fem_corner_sigma_nn_mpa']:.2f}; {row['fem_corner_offset_mm']:+.1f}) | "
              f"{fmt(fine['fem_corner_peak_mpa']) if fine_ok else '—'} | {gov / ref:.2f} | "
              f"{claim:.2f} (s{j}" + (f": {kt_j:.2f}, {fmt(r_j)} ({fmt(r_raw_j)})" if kt_j > 1
                                      else "") + f") | {claim / ref:.2f} | {status}"
              + ("" if ratio is None else " **under**" if ratio < 0.85 else "") + " |")
        if ratio is not None:
            verdict.append((name, i, ratio))
    bad = [v for v in verdict if v[2] < 0.85]
    print(f"\nRows judged (a finite corner radius, own or in the slab, FEM converged or not "
          f"refined): {len(verdict)}; more "
          f"than 15 % under FEM by the corner: {len(bad)} "
          + ", ".join(f"{n} s{i} ({r:.2f})" for n, i, r in bad))
    return 0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("step", choices=["fem", "table"])
    ap.add_argument("--model", default=None, help="models, comma-separated (default: all)")
    ap.add_argument("--only", type=int, action="append", default=None, help="section index")
    ap.add_argument("--fine", type=float, default=3.0, help="fem: elements r/FINE (3, or 6)")
    ap.add_argument("--again", action="store_true")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=120.0, help="fem: gmsh's limit per attempt, s")
    ap.add_argument("--rig", default="/tmp/osteon_junction_rig")
    args = ap.parse_args(argv)
    return run_fem(args) if args.step == "fem" else table(args)


if __name__ == "__main__":
    sys.exit(main())
