"""Printed sections of two engine builds compared, section by section (issue 31's cost work).

    python bench/compare_printed.py --write base.npz      # with the reference build
    python bench/compare_printed.py --against base.npz    # with the changed build
    python bench/compare_printed.py --clipper             # this build against its Clipper2 path

Every rigged model of tests/data (bench/printed_models.py's list) at h = 2 and 8 mm, one
thread, with PrintProfile.fdm(), fdm(infill=0) and resin_hollow(2): each section's printed W
(section_modulus), wall, skin and infill areas. --against prints, per model, profile and h, the
largest difference relative to the section's solid W (for W) or its solid area (for the areas:
wall + skin + infill), and exits 1 when one exceeds --tol, and counts the arrays that are not
equal bit for bit. --models N takes the first N models; --threads N analyses with N workers
(default 1: the base and the changed build may use different counts).
--clipper: the reference is this build with OSTEON_PRINTED_CLIPPER=1 (the walls' inset, skins
and islands by Clipper2's own passes, as before winding_region), in the same process.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import osteon
from osteon.io import load_model
from printed_models import MODELS

PROFILES = {
    "fdm": osteon.PrintProfile.fdm(),
    "fdm0": osteon.PrintProfile.fdm(infill=0.0),
    "resin": osteon.PrintProfile.resin_hollow(2.0),
}
FIELDS = ("section_modulus", "section_wall_area", "section_skin_area", "section_infill_area")
INTERVALS_MM = (2.0, 8.0)


def printed_sections(models: int | None, clipper: bool = False,
                     threads: int = 1) -> dict[str, np.ndarray]:
    """Each model, h and profile's printed sections; `clipper`: by Clipper2's passes only."""
    if clipper:
        os.environ["OSTEON_PRINTED_CLIPPER"] = "1"
    else:
        os.environ.pop("OSTEON_PRINTED_CLIPPER", None)
    out = {}
    for name, mesh, skel, weights in MODELS[:models]:
        m = load_model(mesh, skeleton=skel, weights=weights)
        v, f = np.asarray(m.vertices), np.asarray(m.faces, dtype=np.int32)
        sk = m.skeleton if isinstance(m.skeleton, osteon.Skeleton) else osteon.Skeleton(
            m.heads, m.tails, m.parents, m.bone_names)
        for h in INTERVALS_MM:
            for pname, profile in PROFILES.items():
                a = osteon.analyze(v, f, sk, m.weights, interval=h, threads=threads,
                                   print_profile=profile)
                key = f"{name}|{pname}|{h:g}"
                for field in FIELDS + ("section_solid_modulus",):
                    out[f"{key}|{field}"] = np.asarray(getattr(a, field), dtype=float)
    os.environ.pop("OSTEON_PRINTED_CLIPPER", None)
    return out


def differences(base: dict, new: dict, key: str) -> tuple[np.ndarray, np.ndarray]:
    """Per section of `key`: |dW| / solid W and the largest |d(area)| / solid area."""
    ws = base[f"{key}|section_solid_modulus"]
    area = sum(base[f"{key}|{f}"] for f in FIELDS[1:])
    with np.errstate(invalid="ignore", divide="ignore"):
        dw = np.abs(new[f"{key}|section_modulus"] - base[f"{key}|section_modulus"]) / ws
        da = np.max([np.abs(new[f"{key}|{f}"] - base[f"{key}|{f}"]) / area
                     for f in FIELDS[1:]], axis=0)
    return np.nan_to_num(dw), np.nan_to_num(da)


def compare(base: dict, new: dict, tol: float) -> bool:
    keys = sorted({k.rsplit("|", 1)[0] for k in base})
    ok = True
    print("| model | profile | h (mm) | sections | max dW / W_solid | max d(area) / A | over tol |")
    print("|---|---|---|---|---|---|---|")
    for key in keys:
        ws = base[f"{key}|section_solid_modulus"]
        if f"{key}|section_modulus" not in new:
            print(f"| {key.replace('|', ' | ')} | missing | | | |")
            ok = False
            continue
        if new[f"{key}|section_modulus"].shape != ws.shape:
            print(f"| {key.replace('|', ' | ')} | section count differs | | | |")
            ok = False
            continue
        dw, da = differences(base, new, key)
        over = int(np.sum((dw > tol) | (da > tol)))
        ok &= over == 0
        print(f"| {key.replace('|', ' | ')} | {len(ws)} | {dw.max(initial=0):.2e} | "
              f"{da.max(initial=0):.2e} | {over} |")
    same = sum(np.array_equal(base[k], new[k], equal_nan=True) for k in base if k in new)
    print(f"{len(base) - same} of {len(base)} arrays differ bit for bit")
    return ok


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--write", type=Path)
    ap.add_argument("--against", type=Path)
    ap.add_argument("--models", type=int, default=None)
    ap.add_argument("--clipper", action="store_true")
    ap.add_argument("--tol", type=float, default=1e-6)
    ap.add_argument("--threads", type=int, default=1)
    args = ap.parse_args(argv)
    if (args.write is not None) + (args.against is not None) + args.clipper != 1:
        ap.error("give one of --write FILE, --against FILE, --clipper")
    data = printed_sections(args.models, threads=args.threads)
    if args.clipper:
        reference = printed_sections(args.models, clipper=True, threads=args.threads)
        return 0 if compare(reference, data, args.tol) else 1
    if args.write:
        np.savez_compressed(args.write, **data)
        print(f"wrote {len(data)} arrays to {args.write}")
        return 0
    base = dict(np.load(args.against))
    if args.models is not None:
        names = {name for name, *_ in MODELS[:args.models]}
        base = {k: v for k, v in base.items() if k.split("|")[0] in names}
    return 0 if compare(base, data, args.tol) else 1


if __name__ == "__main__":
    raise SystemExit(main())
