"""Reading a slicer's G-code back (PrusaSlicer's comments: ;Z:, ;TYPE:, ;WIDTH:): the extrusion
moves of each layer, for tests that check what the slicer printed."""

from __future__ import annotations

import re
from collections import defaultdict

import numpy as np

WALL_TYPES = ("Perimeter", "External perimeter")


def layers(path) -> dict[float, list[tuple]]:
    """{z mm: [(type, x0, y0, x1, y1, width mm), ...]}: every move that extrudes and moves in
    x/y (retractions and skirt included; filter by type)."""
    out: dict[float, list[tuple]] = defaultdict(list)
    z = typ = width = None
    x = y = e = 0.0
    relative = False
    with open(path) as fh:
        for line in fh:
            if line.startswith(";Z:"):
                z = round(float(line[3:]), 4)
            elif line.startswith(";TYPE:"):
                typ = line[6:].strip()
            elif line.startswith(";WIDTH:"):
                width = float(line[7:])
            elif line.startswith(("M82", "M83")):
                relative = line.startswith("M83")
            elif line.startswith("G92"):
                m = re.search(r"E([-\d.]+)", line)
                if m:
                    e = float(m.group(1))
            elif line.startswith(("G1 ", "G0 ")):
                nx, ny, ne = x, y, None
                for tok in line.split(";")[0].split()[1:]:
                    if tok[0] == "X":
                        nx = float(tok[1:])
                    elif tok[0] == "Y":
                        ny = float(tok[1:])
                    elif tok[0] == "E":
                        ne = float(tok[1:])
                if ne is not None:
                    de = ne if relative else ne - e
                    if not relative:
                        e = ne
                    if de > 0 and (nx, ny) != (x, y) and z is not None:
                        out[z].append((typ, x, y, nx, ny, width))
                x, y = nx, ny
    return dict(out)


def wall_loops_round(moves) -> int:
    """Perimeter loops of a round island: the distinct radii (from the centre of the external
    perimeter's bounding box) of the wall moves, loops ≥ 0.2 mm apart."""
    ext = np.array([[m[1], m[2]] for m in moves if m[0] == "External perimeter"])
    if len(ext) == 0:
        return 0
    c = 0.5 * (ext.min(0) + ext.max(0))
    r = np.sort([np.hypot(0.5 * (m[1] + m[3]) - c[0], 0.5 * (m[2] + m[4]) - c[1])
                 for m in moves if m[0] in WALL_TYPES])
    return 1 + int(np.sum(np.diff(r) > 0.2))


def extruded_area(moves, kind: str) -> float:
    """mm²: Σ length × width of the moves of one type in a layer (the printed area)."""
    return float(sum(np.hypot(m[3] - m[1], m[4] - m[2]) * m[5] for m in moves if m[0] == kind))
