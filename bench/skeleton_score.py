"""Score osteon.auto_skeleton on the 20 models of issue 35 (cow x4, cow, arm, the test hand, the
16 RigNet models of ../shared/data) against the mesh's extremities (``extremities.py``), and
compare two runs bone by bone (units: mm; 120 mm prints).

    python bench/skeleton_score.py run OUT.npz [--min-t 0.8] [--data ../shared/data]
    python bench/skeleton_score.py diff BASE.npz NEW.npz

``run`` saves every model's bones and extremities (tips, limb radius r, width) and prints, per
model, bones, extremities within 1.5 r of a bone end, and printable extremities (a point within
1.5 r of the tip at least the material's min thickness thick: ``extremities.tip_printable``, the
auto skeleton's own measure) reached; the same for the extremities by the issue's definition
(``extremities.py`` step 5', scored in their radius r_w). ``diff`` lists, per model, the bone count of each run
and every leaf bone of NEW whose tail is no leaf tail of BASE, with its distance to the nearest
extremity tip in that extremity's limb radii (> 3 r: a bone at no extremity), and the
extremities reached by one run and not the other."""

from __future__ import annotations

import argparse
import pickle
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import osteon

sys.path.insert(0, str(Path(__file__).resolve().parent))
from models import load  # noqa: I001  (models puts tests/python on the path)
from extremities import extremities, tip_printable, tip_thickness


def models(data: str):
    """(name, vertices, faces, real skeleton or None) of the 20 models."""
    from osteon.io import load_model
    from test_autoskeleton import hand

    v, f, _, _ = load("cow", subdivisions=1)
    yield "cow_x4", v, f, None
    for name in ("cow", "arm"):
        v, f, real, _ = load(name)
        yield name, v, f, real
    v, f, _fingers, _r = hand()
    yield "hand", v, f, None
    for obj in sorted(Path(data, "RigNet").glob("*_ori.obj")):
        m = load_model(obj, skeleton=obj.with_name(obj.stem + "_rig.txt"), height_mm=120)
        real = m.skeleton if isinstance(m.skeleton, osteon.Skeleton) else osteon.Skeleton(
            m.heads, m.tails, m.parents)
        yield obj.stem.split("_")[0], np.asarray(m.vertices), np.asarray(m.faces), real


def leaves(parents: np.ndarray) -> np.ndarray:
    has_child = np.zeros(len(parents), bool)
    has_child[parents[parents >= 0]] = True
    return ~has_child


def run(out: str, min_t: float, data: str, cache: str | None = None,
        voxel_tips: bool = False) -> None:
    from bench_autoskeleton import limb_radii
    from osteon.autoskeleton import split_pieces
    from osteon.autoskeleton.mesh import check_mesh

    saved = {}
    tot = np.zeros(10, int)
    print("| model | bones | CPU s | extremities within 1.5 r | printable extremities within 1.5 r "
          "| issue's extremities within 1.5 r_w | printable | rig tips within 1.5 r |")
    print("|---|---|---|---|---|---|---|---|")
    for name, v, f, real in models(data):
        c = time.process_time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            sk, _w = osteon.auto_skeleton(v, f, min_thickness=min_t)
        cpu = time.process_time() - c
        wv, wf, _ = check_mesh(v, f)
        tag = "_voxel" if voxel_tips else ""
        key = Path(cache, f"{name}_{min_t}{tag}.pkl") if cache else None
        if key is not None and key.exists():  # (the extremities do not depend on the bones)
            ex, thin_tip, old_flag, ip = pickle.loads(key.read_bytes())
        else:
            p = split_pieces(wv, wf)
            ex = extremities(wv, wf, p, mesh_tips=not voxel_tips)
            thin_tip = tip_printable(wv, wf, p, ex, min_t)
            old_flag = tip_thickness(wv, wf, p, ex) >= min_t  # (the flag before session 11)
            ip = tip_printable(wv, wf, p, ex.issue, min_t)
            if key is not None:
                key.write_bytes(pickle.dumps((ex, thin_tip, old_flag, ip)))
        ends = np.concatenate([sk.heads, sk.tails])
        x = np.linalg.norm(ex.tips[:, None] - ends[None], axis=2).min(1) / ex.radius
        printable = thin_tip
        rig = ""
        if real is not None and name not in ("cow", "arm"):
            d, _e = limb_radii(v, real, ends)
            rig = f"{(d <= 1.5).sum()}/{len(d)}"
            tot[4:6] += [(d <= 1.5).sum(), len(d)]
        ok = x <= 1.5
        tot[:4] += [ok.sum(), len(x), (ok & thin_tip).sum(), thin_tip.sum()]
        iex = ex.issue  # the issue's definition (extremities.py step 5'), radius r_w
        xi = np.linalg.norm(iex.tips[:, None] - ends[None], axis=2).min(1) / iex.radius
        oki = xi <= 1.5
        tot[6:] += [oki.sum(), len(xi), (oki & ip).sum(), ip.sum()]
        print(f"| {name} | {sk.num_bones} | {cpu:.2f} | {ok.sum()}/{len(x)} | "
              f"{(ok & thin_tip).sum()}/{thin_tip.sum()} | {oki.sum()}/{len(xi)} | "
              f"{(oki & ip).sum()}/{ip.sum()} | {rig} |", flush=True)
        saved[name] = {"heads": sk.heads, "tails": sk.tails, "parents": sk.parents, "tips": ex.tips,
                       "radius": ex.radius, "width": ex.width, "printable": printable,
                       "itips": iex.tips, "iradius": iex.radius, "iwidth": iex.width,
                       "iprintable": ip, "printable_old": old_flag}
    print(f"| all | | | {tot[0]}/{tot[1]} | {tot[2]}/{tot[3]} | {tot[6]}/{tot[7]} | "
          f"{tot[8]}/{tot[9]} | {tot[4]}/{tot[5]} |")
    np.savez(out, **{f"{m}:{k}": a for m, d in saved.items() for k, a in d.items()})


def _load(path: str, issue: bool = False) -> dict[str, dict[str, np.ndarray]]:
    """Per model its saved arrays; with ``issue`` the extremities by the issue's definition
    (``itips``, ``iradius``, ...) in place of the old ones."""
    z = np.load(path)
    out: dict[str, dict[str, np.ndarray]] = {}
    for key in z.files:
        m, k = key.split(":")
        out.setdefault(m, {})[k] = z[key]
    if issue:
        for d in out.values():
            for k in ("tips", "radius", "width", "printable"):
                d[k] = d["i" + k]
    return out


def diff(base_path: str, new_path: str, issue: bool = False) -> None:
    base, new = _load(base_path, issue), _load(new_path, issue)
    total_new, total_far = 0, 0
    for m in new:
        b, n = base[m], new[m]
        lb, ln = leaves(b["parents"]), leaves(n["parents"])
        old_tails = b["tails"][lb]
        fresh = [t for t in n["tails"][ln]
                 if not len(old_tails) or np.linalg.norm(old_tails - t, axis=1).min() > 1e-6]
        tips, r = n["tips"], n["radius"]
        far = [float((np.linalg.norm(tips - t, axis=1) / r).min()) if len(tips) else np.inf
               for t in fresh]

        rb, rn = (np.linalg.norm(tips[:, None] - np.concatenate([d["heads"], d["tails"]])[None],
                                 axis=2).min(1) / r <= 1.5 for d in (b, n))
        gained, lost = np.flatnonzero(rn & ~rb), np.flatnonzero(rb & ~rn)
        total_new += len(fresh)
        total_far += sum(q > 3 for q in far)
        if len(b["parents"]) == len(n["parents"]) and not fresh and not len(gained) \
                and not len(lost):
            continue
        print(f"{m}: bones {len(b['parents'])} -> {len(n['parents'])}; extremities "
              f"{rb.sum()} -> {rn.sum()} of {len(tips)} (gained {gained.tolist()}, lost "
              f"{lost.tolist()}); new leaf bones {len(fresh)}, nearest extremity (r): "
              f"{[round(q, 1) for q in far]}")
    print(f"all: {total_new} new leaf bones, {total_far} of them > 3 r from every extremity")


def misses(path: str, issue: bool = False) -> None:
    """Every extremity no bone end reaches: model, tip mm, r mm, width mm, distance (r), and
    where the tip lies from the nearest bone end along its bone's axis (mm past the end,
    mm off the axis: an end bone that reaches its limb's end with the extremity beside it, a
    corner of a wide flat end, reads small along and large off)."""
    for m, d in _load(path, issue).items():
        ends = np.concatenate([d["heads"], d["tails"]])
        x = np.linalg.norm(d["tips"][:, None] - ends[None], axis=2).min(1) / d["radius"]
        nb = len(d["heads"])
        for i in np.flatnonzero(x > 1.5):
            tip = d["tips"][i]
            k = int(np.argmin(np.linalg.norm(ends - tip, axis=1)))
            b, at_tail = k % nb, k >= nb
            ax = d["tails"][b] - d["heads"][b] if at_tail else d["heads"][b] - d["tails"][b]
            ax = ax / max(float(np.linalg.norm(ax)), 1e-12)
            rel = tip - ends[k]
            along = float(rel @ ax)
            off = float(np.linalg.norm(rel - along * ax))
            print(f"{m} #{i} tip {np.round(tip, 1).tolist()} r {d['radius'][i]:.2f} "
                  f"width {d['width'][i]:.2f} printable {bool(d['printable'][i])}: {x[i]:.1f} r; "
                  f"from bone {b}'s {'tail' if at_tail else 'head'} {along:.1f} mm along, "
                  f"{off:.1f} mm off its axis")


def printable(paths: list[str], min_t: float, data: str) -> None:
    """Per model, for each run: extremities reached / all, printable ones (``tip_thickness``
    >= ``min_t``) reached / printable."""
    from extremities import VOXELS, Extremities
    from osteon.autoskeleton import split_pieces
    from osteon.autoskeleton.mesh import check_mesh

    runs = [_load(p) for p in paths]
    tot = np.zeros((len(runs), 4), int)
    for name, v, f, _real in models(data):
        wv, wf, _ = check_mesh(v, f)
        d0 = runs[0][name]
        p = split_pieces(wv, wf)
        h = float(np.ptp(wv[p.vertices_of([p.main, *p.joined])], axis=0).max()) / VOXELS
        ex = Extremities(d0["tips"], d0["radius"], d0["width"], d0["width"], h)  # (as saved)
        ok_t = tip_thickness(wv, wf, p, ex) >= min_t
        cells = []
        for i, run in enumerate(runs):
            d = run[name]
            ends = np.concatenate([d["heads"], d["tails"]])
            ok = np.linalg.norm(d["tips"][:, None] - ends[None], axis=2).min(1) / d["radius"] <= 1.5
            tot[i] += [ok.sum(), len(ok), (ok & ok_t).sum(), ok_t.sum()]
            cells.append(f"{ok.sum()}/{len(ok)}, {(ok & ok_t).sum()}/{ok_t.sum()}")
        print(f"| {name} | " + " | ".join(cells) + " |", flush=True)
    print("| all | " + " | ".join(f"{a}/{b}, {c}/{e}" for a, b, c, e in tot) + " |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("out")
    r.add_argument("--min-t", type=float, default=0.8)
    r.add_argument("--cache", help="a folder for each model's extremities (reused run to run)")
    r.add_argument("--voxel-tips", action="store_true",
                   help="tips and radii on the voxels only (extremities.py without step 6)")
    r.add_argument("--data", default=str(Path(__file__).resolve().parents[2] / "shared" / "data"))
    d = sub.add_parser("diff")
    d.add_argument("base")
    d.add_argument("new")
    d.add_argument("--issue", action="store_true", help="the issue's extremities (step 5')")
    ms = sub.add_parser("misses")
    ms.add_argument("path")
    ms.add_argument("--issue", action="store_true", help="the issue's extremities (step 5')")
    pr = sub.add_parser("printable")
    pr.add_argument("paths", nargs="+")
    pr.add_argument("--min-t", type=float, default=0.8)
    pr.add_argument("--data", default=str(Path(__file__).resolve().parents[2] / "shared" / "data"))
    args = ap.parse_args()
    if args.cmd == "printable":
        printable(args.paths, args.min_t, args.data)
    elif args.cmd == "misses":
        misses(args.path, args.issue)
    elif args.cmd == "run":
        run(args.out, args.min_t, args.data, args.cache, args.voxel_tips)
    else:
        diff(args.base, args.new, args.issue)


if __name__ == "__main__":
    main()
