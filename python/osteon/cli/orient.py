"""``osteon analyze --orient``: the best print orientations (docs/printing.md)."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def best_orientation_of(args, model, analysis):
    """best_orientation for ``analyze --orient``; writes --orient-out. Returns the result."""
    from ..orientation import best_orientation

    if args.orient_samples < 1:
        raise ValueError(f"--orient-samples must be >= 1, got {args.orient_samples}")
    if args.orient_out and Path(args.orient_out).suffix.lower() not in (
        ".obj", ".off", ".ply", ".stl"
    ):
        raise ValueError(f"--orient-out {args.orient_out}: use an .obj, .off, .ply or .stl name")
    from .common import settings_from_args

    settings = settings_from_args(args)
    profile = settings.profile()
    printed = {} if profile.is_solid else {
        # the printed section turns with the build direction: the best candidates are analysed
        # again with the profile (osteon.best_orientation, docs/printing.md)
        "print_profile": profile,
        "model": (model.vertices, model.faces, model.skeleton, model.weights),
        "engine_options": {"junctions": settings.junctions}}
    o = best_orientation(
        analysis,
        samples=args.orient_samples,
        base="flat" if args.orient_flat else None,
        vertices=model.vertices if args.orient_flat else None,
        **printed,
    )
    if args.orient_out:
        from ..io import write_mesh

        write_mesh(args.orient_out, o.rotate(model.vertices), model.faces)
    return o


def orientation_table(o) -> str:
    """The best few build directions, one line each, and the current one."""
    head = f"{'#':>2} {'build direction (x, y, z)':<28} {'worst σ/[σ]':>11} {'turn °':>7}  "
    lines = [head + "governing limit"]
    lines.append("-" * len(lines[0]))
    ref = o.reference_direction
    for k, c in enumerate(o.candidates, 1):
        d = c["direction"]
        turn = np.degrees(np.arccos(np.clip(float(d @ ref), -1, 1)))
        lim = "across layers" if c["across_layers"] else "along layers"
        lines.append(f"{k:>2} ({d[0]:+.3f}, {d[1]:+.3f}, {d[2]:+.3f}){'':<6} "
                     f"{c['worst_ratio']:>11.3f} {turn:>7.1f}  {lim}")
    lines.append(f"current ({ref[0]:+.3f}, {ref[1]:+.3f}, {ref[2]:+.3f}): worst σ/[σ] "
                 f"{o.reference_ratio:.3f}; best is {o.improvement:.2f}x stronger "
                 f"(layer ratio {o.layer_strength_ratio:g})")
    return "\n".join(lines)


def orientation_json(o) -> dict:
    """The report's ``orientation`` block."""
    def cand(c):
        out = {"direction": [float(x) for x in c["direction"]],
               "rotation": [[float(x) for x in row] for row in c["rotation"]],
               "worst_ratio": float(c["worst_ratio"]),
               "worst_section": int(c["worst_section"]),
               "limit": "across layers" if c["across_layers"] else "along layers"}
        if "base_area_mm2" in c:
            out["base_area_mm2"] = float(c["base_area_mm2"])
        return out

    return {"best": cand(o.candidates[0]), "candidates": [cand(c) for c in o.candidates],
            "reference_direction": [float(x) for x in o.reference_direction],
            "reference_ratio": float(o.reference_ratio), "samples": len(o.ratios),
            "base": o.base}
