"""Section audit per real model (issue 12): sections, flags by kind, max stress, slivers.

    python bench/section_audit.py [model.obj ...]       # default: every RigNet OBJ + rig,
                                                        # libigl, Hyperspectral models
    OSTEON_DATA=DIR python bench/section_audit.py         # the shared models' folder (default:
                                                        # ../shared/data beside the clone)

Prints one Markdown row per model: sections, count of each flag, max stress (MPa) and the flags
of the section it sits on, and the weak sections whose area is below a tenth of the median area
of their bone's sections ("slivers"), and how many of those are isolated drops (below a tenth of
their nearest analysed interior neighbours on the bone too; the others are parts that really are
thin there, e.g. a tapering tail whose bone also cuts the body). Run it with two builds to compare before / after.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np
import osteon
from osteon.io import load_model

# The shared models: $OSTEON_DATA, else ../shared/data beside the clone (no test reads them).
DATA = Path(os.environ.get("OSTEON_DATA", Path(__file__).resolve().parents[2] / "shared" / "data"))


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
    slivers = isolated = 0
    for b in np.unique(a.section_bone):
        sel = (a.section_bone == b) & ok
        if not sel.any():
            continue
        med = np.median(a.section_area[sel])
        small = np.flatnonzero(sel & a.weak & (a.section_area < 0.1 * med))
        slivers += len(small)
        # Isolated: also below a tenth of its nearest analysed interior neighbours on the bone
        # (a sudden drop, not a part that really is thin there, like a tapering tail).
        inner = np.flatnonzero(sel & (a.section_kind == 0))
        inner = inner[np.argsort(a.section_param[inner])]
        for i in small:
            k = np.searchsorted(a.section_param[inner], a.section_param[i])
            nb = [inner[j] for j in (k - 1, k + 1 if k < len(inner) and inner[k] == i else k)
                  if 0 <= j < len(inner) and inner[j] != i]
            if all(a.section_area[i] < 0.1 * a.section_area[j] for j in nb):
                isolated += 1
    w = a.weakest_section
    at = a.flag_names(w) if w >= 0 else []
    return {"sections": a.num_sections, "flags": flags, "max": a.max_stress, "at": at,
            "slivers": slivers, "isolated": isolated, "loose": len(getattr(a, "loose_pieces", []))}


def main(argv: list[str]) -> None:
    if not argv and not (DATA / "SOURCES.md").is_file():
        raise SystemExit(f"section_audit: the shared models are not at {DATA} (set OSTEON_DATA "
                         "to their folder, or give model files)")
    todo = [(Path(p), None, None) for p in argv] if argv else models()
    print("| model | sections | flags | max stress MPa (flags there) | weak < 1/10 bone median "
          "| of which isolated drops | loose |")
    print("|---|---|---|---|---|---|---|")
    for mesh, skel, weights in todo:
        try:
            r = audit(mesh, skel, weights)
        except Exception as e:  # noqa: BLE001 - report and go on
            print(f"| {mesh.stem} | error: {e} | | | | | |")
            continue
        fl = ", ".join(f"{k} {v}" for k, v in r["flags"].items() if v)
        print(f"| {mesh.stem} | {r['sections']} | {fl} | {r['max']:.4g} ({', '.join(r['at'])})"
              f" | {r['slivers']} | {r['isolated']} | {r['loose']} |", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
