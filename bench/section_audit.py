"""Section audit per real model (issue 12): sections, flags by kind, max stress, slivers.

    python bench/section_audit.py [model.obj ...]       # default: every RigNet OBJ + rig,
                                                        # libigl, Hyperspectral models
    /work/main/.venv/bin/python bench/section_audit.py   # the same with another build

Prints one Markdown row per model: sections, count of each flag, max stress (MPa) and the flags
of the section it sits on, and the weak sections whose area is below a tenth of the median area
of their bone's sections ("slivers"). Run it with two builds to compare before / after.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import osteon
from osteon.io import load_model

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
if not DATA.exists():
    DATA = Path("/work/shared/data")


def models() -> list[tuple[Path, Path | None, Path | None]]:
    out = []
    for obj in sorted((DATA / "RigNet").glob("*_ori.obj")):
        rig = obj.with_name(obj.name.replace(".obj", "_rig.txt"))
        out.append((obj, rig if rig.exists() else None, None))
    for name in ("arm", "elephant"):
        out.append((DATA / "libigl-tutorial-data" / f"{name}.obj", None, None))
    hs = DATA / "Hyperspectral-Inverse-Skinning"
    out.append((hs / "cheburashka.obj", hs / "cheburashka.tgf", hs / "cheburashka.DMAT"))
    out.append((hs / "cow_clean.obj", hs / "cow.tgf", hs / "cow.DMAT"))
    return out


def audit(mesh, skel, weights) -> dict:
    m = load_model(str(mesh), skeleton=None if skel is None else str(skel),
                   weights=None if weights is None else str(weights), height_mm=120.0)
    sk = m.skeleton if isinstance(m.skeleton, osteon.Skeleton) else osteon.Skeleton(
        m.heads, m.tails, m.parents, m.bone_names)
    a = osteon.analyze(np.asarray(m.vertices), np.asarray(m.faces, dtype=np.int32), sk,
                       m.weights)
    flags = {name: int(np.count_nonzero(a.section_flags & bit))
             for name, bit in osteon.SECTION_FLAGS.items()}
    ok = np.isfinite(a.stress) & (a.section_area > 0)
    slivers = 0
    for b in np.unique(a.section_bone):
        sel = (a.section_bone == b) & ok
        if not sel.any():
            continue
        med = np.median(a.section_area[sel])
        slivers += int(np.count_nonzero(sel & a.weak & (a.section_area < 0.1 * med)))
    w = a.weakest_section
    at = a.flag_names(w) if w >= 0 else []
    return {"sections": a.num_sections, "flags": flags, "max": a.max_stress, "at": at,
            "slivers": slivers, "loose": len(getattr(a, "loose_pieces", []))}


def main(argv: list[str]) -> None:
    todo = [(Path(p), None, None) for p in argv] if argv else models()
    print("| model | sections | flags | max stress MPa (flags there) | weak slivers | loose |")
    print("|---|---|---|---|---|---|")
    for mesh, skel, weights in todo:
        try:
            r = audit(mesh, skel, weights)
        except Exception as e:  # noqa: BLE001 - report and go on
            print(f"| {mesh.stem} | error: {e} | | | | |")
            continue
        fl = ", ".join(f"{k} {v}" for k, v in r["flags"].items() if v)
        print(f"| {mesh.stem} | {r['sections']} | {fl} | {r['max']:.4g} ({', '.join(r['at'])})"
              f" | {r['slivers']} | {r['loose']} |", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
