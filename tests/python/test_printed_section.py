"""The printed section (issue 31): walls, skins and sparse infill as a slicer prints them.

Closed forms (a layer of a rod is a tube of the wall depth; a solid profile changes nothing; a
lying bar's skins and walls) and PrusaSlicer itself: rods sliced by ``prusa-slicer`` whose
printed section is rebuilt from the G-code's extrusion moves (strips of their ``;WIDTH:``) and
compared with osteon's (docs/printing.md, "The printed section")."""

from __future__ import annotations

import math
import shutil
import subprocess

import numpy as np
import osteon
import pytest
from osteon.printed import infill_stiffness, line_spacing, wall_depth
from shapes import circle, prism, rectangle

FDM = osteon.PrintProfile.fdm  # PrusaSlicer-like: 2 x 0.45 mm perimeters, 0.2 mm layers


def _bar(profile_2d, length, axis):
    """A prism of `profile_2d` (in the plane across `axis`) from 0 to `length` along axis x or
    z, standing or lying on the bed z = 0, and its one-bone skeleton along its axis."""
    v, f = prism(profile_2d, length, stations=3)
    if axis == "z":  # (x, y, z) -> (y, z, x): the bar stands along z, the profile in x-y
        v = v[:, [1, 2, 0]]
        head, tail = [0.0, 0.0, 0.0], [0.0, 0.0, length]
    else:
        lift = -profile_2d[:, 1].min()
        v = v + [0.0, 0.0, lift]
        head, tail = [0.0, 0.0, lift], [length, 0.0, lift]
    return v, f, osteon.Skeleton([head], [tail], [-1], ["bar"])


def _middle(a, length):
    """Index of the interior section nearest the bar's middle."""
    i = np.flatnonzero((a.section_kind == 0) & a.valid)
    return i[np.argmin(np.abs(a.section_param[i] - length / 2))]


def _tube_modulus(r_out, r_in, n):
    return osteon.section_properties(circle(r_out, n), [circle(r_in, n)])["modulus"]


# ---------------------------------------------------------------- closed forms


def test_wall_depth_is_prusaslicers_spacing_rule():
    # Flow::spacing: w - h (1 - pi/4); walls w/2 + s/2 + (P - 1) s.
    s = line_spacing(0.45, 0.2)
    assert s == pytest.approx(0.45 - 0.2 * (1 - math.pi / 4), rel=1e-12)
    assert wall_depth(FDM(perimeters=2)) == pytest.approx(0.225 + 1.5 * s, rel=1e-12)
    assert wall_depth(FDM(perimeters=3)) == pytest.approx(0.225 + 2.5 * s, rel=1e-12)
    assert wall_depth(FDM(perimeters=0)) == 0.0


def test_standing_rod_layer_is_the_tube_of_the_wall_depth():
    n, r, length = 256, 5.0, 20.0
    v, f, sk = _bar(circle(r, n), length, "z")
    profile = FDM(infill=0.0)
    a = osteon.analyze(v, f, sk, interval=2.0, print_profile=profile)
    i = _middle(a, length)
    # the inset n-gon's circumradius is R - t_w / cos(pi / n)
    expected = _tube_modulus(r, r - wall_depth(profile) / math.cos(math.pi / n), n)
    assert a.section_modulus[i] == pytest.approx(expected, rel=0.01)
    assert a.section_modulus[i] / a.section_solid_modulus[i] == pytest.approx(0.519, abs=0.002)
    # the stress follows the printed W
    assert a.stress[i] == pytest.approx(a.moment[i] / a.section_modulus[i], rel=1e-12)
    assert a.section_infill_area[i] + a.section_wall_area[i] == pytest.approx(
        a.section_area[i], rel=1e-6)
    assert a.section_skin_area[i] == pytest.approx(0.0, abs=1e-6)


def test_solid_profile_is_bit_identical():
    v, f, sk = _bar(circle(4.0, 64), 30.0, "x")
    base = osteon.analyze(v, f, sk, interval=1.5, keep_outlines=True)
    for profile in (osteon.PrintProfile.solid(), FDM(infill=1.0), "solid"):
        a = osteon.analyze(v, f, sk, interval=1.5, keep_outlines=True, print_profile=profile)
        for name in ("section_modulus", "stress", "stress_ratio", "vertex_stress",
                     "outline_points"):
            np.testing.assert_array_equal(getattr(a, name), getattr(base, name))
        np.testing.assert_array_equal(a.section_solid_modulus, base.section_modulus)
        assert all(loops == [] for loops in a.infill_loops)


def test_full_infill_is_about_solid():
    # 100 % infill: eta = 1 on every pattern; with kind fdm it is solid (no print code).
    assert infill_stiffness("gyroid", 1.0) == (1.0, 1.0)
    v, f, sk = _bar(circle(6.0, 128), 20.0, "x")
    a = osteon.analyze(v, f, sk, print_profile=FDM(infill=0.999, pattern="grid"))
    ok = a.valid
    np.testing.assert_allclose(a.section_modulus[ok], a.section_solid_modulus[ok], rtol=0.005)


def test_lying_bar_has_skins_top_and_bottom_and_walls_at_the_sides():
    # A 12 (y) x 8 (z) bar lying along x, built along z: walls t_w deep at the sides (y), skins
    # 4 x 0.2 mm deep at the top and bottom (z), sparse infill between.
    b, h, length = 12.0, 8.0, 20.0
    v, f, sk = _bar(rectangle(b, h), length, "x")
    profile = FDM(infill=0.15)
    a = osteon.analyze(v, f, sk, print_profile=profile, keep_outlines=True)
    i = _middle(a, length)
    tw, ts = wall_depth(profile), 0.8
    # (the walls' depth across the layers is t_w cos(theta), taken at cos >= 1e-3)
    eroded = (b - 2 * tw) * (h - 2e-3 * tw)
    assert a.section_wall_area[i] == pytest.approx(b * h - eroded, rel=1e-3)
    assert a.section_wall_area[i] == pytest.approx(2 * tw * h, rel=2e-3)
    assert a.section_skin_area[i] == pytest.approx(eroded - (b - 2 * tw) * (h - 2 * ts), rel=1e-3)
    assert a.section_infill_area[i] == pytest.approx((b - 2 * tw) * (h - 2 * ts), rel=1e-3)
    # the sparse region's loop is that rectangle, on the section plane
    (loop,) = a.infill_loops[i]
    assert np.ptp(loop[:, 1]) == pytest.approx(b - 2 * tw, rel=1e-3)
    assert np.ptp(loop[:, 2]) == pytest.approx(h - 2 * ts, rel=1e-3)
    # transformed section: gyroid at 15 % in the layer plane (stress along x): eta = 0.15^2
    eta = infill_stiffness("gyroid", 0.15)[1]
    bi, hi = b - 2 * tw, h - 2 * ts
    ju = (b * h**3 - (1 - eta) * bi * hi**3) / 12  # about y (z^2)
    jv = (h * b**3 - (1 - eta) * hi * bi**3) / 12
    expected = 1.0 / math.hypot(b / 2 / jv, h / 2 / ju)
    assert a.section_modulus[i] == pytest.approx(expected, rel=1e-3)


def test_resin_shell_is_the_tube_whatever_the_build_direction():
    n, r, length = 256, 5.0, 20.0
    v, f, sk = _bar(circle(r, n), length, "x")
    expected = _tube_modulus(r, r - 2.0 / math.cos(math.pi / n), n)
    for build in ((0, 0, 1), (1, 0, 0), (0, 1, 1)):
        a = osteon.analyze(v, f, sk, build_direction=build,
                           print_profile=osteon.PrintProfile.resin_hollow(2.0))
        assert a.section_modulus[_middle(a, length)] == pytest.approx(expected, rel=0.01)


def test_a_section_thinner_than_its_shell_is_all_shell_and_a_thicker_one_keeps_its_core():
    """The inset is skipped where the section's second moments prove it empty (an inscribed
    disc of radius r needs pi r^4 / 4 in every direction): a 2 mm shell of a rod of r = 1.9 mm
    is the whole section, one of r = 2.3 mm keeps the core of radius 0.3 mm (closed form), to
    the shell's precision: its outline and its round joins each within 1 % of its depth."""
    n, length = 256, 20.0
    shell = osteon.PrintProfile.resin_hollow(2.0)
    tolerance = 2 * 0.01 * 2.0  # mm on the core's radius
    for r in (1.9, 2.3):
        v, f, sk = _bar(circle(r, n), length, "z")
        a = osteon.analyze(v, f, sk, interval=2.0, print_profile=shell)
        i = _middle(a, length)
        core = max(r - 2.0 / math.cos(math.pi / n), 0.0)
        if core == 0:
            assert a.section_infill_area[i] == 0.0
        else:
            assert (math.pi * (core - tolerance) ** 2 < a.section_infill_area[i]
                    < math.pi * (core + tolerance) ** 2)
        assert a.section_wall_area[i] + a.section_infill_area[i] == pytest.approx(
            a.section_area[i], rel=1e-3)
        if core == 0:
            assert a.section_modulus[i] == a.section_solid_modulus[i]
        else:
            assert a.section_modulus[i] < a.section_solid_modulus[i]


def test_culling_uses_the_printed_modulus():
    v, f, sk = _bar(circle(5.0, 64), 40.0, "x")
    a = osteon.analyze(v, f, sk, print_profile=FDM(infill=0.0), build_direction=(1, 0, 0))
    ok = a.valid
    np.testing.assert_array_equal(
        a.culled[ok], a.section_modulus[ok] > a.max_moment / a.section_allowable[ok])
    assert np.all(a.section_modulus[ok] < a.section_solid_modulus[ok])


# ---------------------------------------------------------------- PrusaSlicer

PRUSA = shutil.which("prusa-slicer")
needs_slicer = pytest.mark.skipif(PRUSA is None, reason="prusa-slicer is not installed "
                                  "(apt-get install prusa-slicer; .ci/run installs it)")


def _write_stl(path, v, f):
    tri = v[f].astype("<f4")
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    rec = np.zeros(len(f), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    rec["n"], rec["v"] = n, tri
    with open(path, "wb") as fh:
        fh.write(b"\0" * 80 + np.uint32(len(f)).tobytes() + rec.tobytes())


def _slice(tmp_path, v, f, infill_percent):
    """G-code of the mesh as PrusaSlicer prints it with the FDM() profile's settings."""
    stl, gcode = tmp_path / "part.stl", tmp_path / "part.gcode"
    _write_stl(stl, v, f)
    cmd = [PRUSA, "--export-gcode", "--perimeters", "2", "--extrusion-width", "0.45",
           "--layer-height", "0.2", "--first-layer-height", "0.2", "--top-solid-layers", "4",
           "--bottom-solid-layers", "4", "--fill-density", f"{infill_percent}%",
           "--fill-pattern", "gyroid", "--solid-infill-below-area", "70", "--skirts", "0",
           "-o", str(gcode), str(stl)]
    subprocess.run(cmd, check=True, capture_output=True, timeout=120)
    return gcode.read_text()


def _extrusions(gcode):
    """Extrusion moves (layer top z, layer height, type, width, start xy, end xy); absolute E."""
    x = y = None
    e = 0.0
    kind = width = height = z = None
    for line in gcode.splitlines():
        if line.startswith(";"):
            key, _, value = line[1:].partition(":")
            if key == "TYPE":
                kind = value.strip()
            elif key == "WIDTH":
                width = float(value)
            elif key == "HEIGHT":
                height = float(value)
            elif key == "Z":
                z = float(value)
            continue
        words = line.split(";")[0].split()
        if not words or words[0] not in ("G1", "G92"):
            continue
        vals = {w[0]: float(w[1:]) for w in words[1:] if w[0] in "XYZE" and len(w) > 1}
        if words[0] == "G92":
            e = vals.get("E", e)
            continue
        nx, ny = vals.get("X", x), vals.get("Y", y)
        if "E" in vals and vals["E"] > e and x is not None and (nx, ny) != (x, y):
            yield z, height, kind, width, (x, y), (nx, ny)
        e = vals.get("E", e)
        x, y = nx, ny


SPARSE = "Internal infill"  # every other type (perimeters, solid infill, gap fill) is solid


def _gcode_section(gcode, axis, centre):
    """The printed section rebuilt from the G-code's strips, as two shapely regions: every
    extrusion but the sparse infill ("solid"), and every extrusion ("union"). Standing bar
    (axis z): the middle layer's strips. Lying bar (axis x): each layer's strips cut by the
    plane x = centre[0], as rectangles of the layer's height in (y, z)."""
    from shapely.geometry import LineString, box
    from shapely.ops import unary_union

    moves = [m for m in _extrusions(gcode) if m[2] not in ("Skirt/Brim", "Wipe tower")]
    solid, every = [], []
    if axis == "z":
        zs = sorted({m[0] for m in moves})
        layer = zs[len(zs) // 2]
        for z, _, kind, w, p, q in moves:
            if z == layer:
                strip = LineString([p, q]).buffer(w / 2)
                every.append(strip)
                if kind != SPARSE:
                    solid.append(strip)
    else:
        x0 = centre[0]
        plane = LineString([(x0, centre[1] - 1e3), (x0, centre[1] + 1e3)])
        for z, h, kind, w, p, q in moves:
            if min(p[0], q[0]) - w > x0 or max(p[0], q[0]) + w < x0:
                continue
            cut = LineString([p, q]).buffer(w / 2).intersection(plane)
            if cut.is_empty:
                continue
            ys = np.asarray(cut.bounds)[[1, 3]]
            rect = box(ys[0], z - h, ys[1], z)
            every.append(rect)
            if kind != SPARSE:
                solid.append(rect)
    return unary_union(solid), unary_union(every)


def _modulus(region):
    """W of a shapely region (holes, several pieces) at its hull's vertices."""
    parts = getattr(region, "geoms", [region])
    area, first, second = 0.0, np.zeros(2), np.zeros((2, 2))
    for poly in parts:
        for ring, sign in [(poly.exterior, 1.0)] + [(r, -1.0) for r in poly.interiors]:
            props = osteon.section_properties(np.asarray(ring.coords)[:-1])
            a, c = props["area"], np.asarray(props["centroid"])
            juu, juv, jvv = props["second_moment"]
            area += sign * a
            first += sign * a * c
            second += sign * (np.array([[juu, juv], [juv, jvv]]) + a * np.outer(c, c))
    c = first / area
    j = second - area * np.outer(c, c)
    hull = np.asarray(region.convex_hull.exterior.coords)[:-1]
    return 1.0 / np.max(np.linalg.norm(np.linalg.solve(j, (hull - c).T), axis=0))


ROUND, ELLIPSE = circle(5.0, 128), circle(1.0, 128) * [6.0, 3.5]


@needs_slicer
@pytest.mark.parametrize("shape, axis, infill", [
    ("round", "z", 0), ("ellipse", "z", 0), ("round", "x", 0), ("ellipse", "x", 0),
    ("round", "z", 15), ("ellipse", "z", 15),  # the slicer fills these small layers solid
])
def test_walls_skins_and_solid_fill_match_prusaslicer(tmp_path, shape, axis, infill):
    """Where the printed section is walls, skins and solid fill: osteon's W within 8 % of the
    W of the strips PrusaSlicer extrudes."""
    length = 10.0
    v, f, sk = _bar(ROUND if shape == "round" else ELLIPSE, length, axis)
    gcode = _slice(tmp_path, v, f, infill)
    moves = [m for m in _extrusions(gcode) if m[2] != "Skirt/Brim"]
    xy = np.array([m[4] for m in moves])
    centre = (xy.min(0) + xy.max(0)) / 2
    solid, every = _gcode_section(gcode, axis, centre)
    assert solid.area == pytest.approx(every.area, rel=0.02), "sparse infill in this section"
    a = osteon.analyze(v, f, sk, interval=1.0, print_profile=FDM(infill=infill / 100))
    i = _middle(a, length)
    w_slicer, w_osteon = _modulus(every), a.section_modulus[i]
    print(f"{shape} {axis} {infill}%: slicer W {w_slicer:.2f}, osteon {w_osteon:.2f}, "
          f"solid {a.section_solid_modulus[i]:.2f} mm³")
    assert w_osteon == pytest.approx(w_slicer, rel=0.08)


@needs_slicer
@pytest.mark.parametrize("shape, axis", [("round8", "z"), ("round", "x"), ("ellipse", "x")])
def test_sparse_infill_lies_between_walls_only_and_the_extruded_union(tmp_path, shape, axis):
    """With 15 % gyroid: osteon's W between the W of everything but the sparse infill and the
    W of every strip counted solid (8 % margin on each side). The lying bars are 30 mm long:
    their layers' infill islands (length x width) stay above solid_infill_below_area."""
    length = 10.0 if axis == "z" else 30.0
    profile_2d = {"round": ROUND, "ellipse": ELLIPSE, "round8": circle(8.0, 160)}[shape]
    v, f, sk = _bar(profile_2d, length, axis)
    gcode = _slice(tmp_path, v, f, 15)
    moves = [m for m in _extrusions(gcode) if m[2] != "Skirt/Brim"]
    xy = np.array([m[4] for m in moves])
    centre = (xy.min(0) + xy.max(0)) / 2
    solid, every = _gcode_section(gcode, axis, centre)
    assert solid.area < 0.9 * every.area, "no sparse infill in this section"
    a = osteon.analyze(v, f, sk, interval=1.0, print_profile=FDM(infill=0.15))
    i = _middle(a, length)
    low, high, w = _modulus(solid), _modulus(every), a.section_modulus[i]
    print(f"{shape} {axis} 15%: walls-only W {low:.2f}, osteon {w:.2f}, union {high:.2f}, "
          f"solid {a.section_solid_modulus[i]:.2f} mm³")
    assert w <= 1.08 * high  # never stronger than every strip counted solid
    # Lying: the narrow skins under the slopes widened by 3 lines into the infill, as
    # PrusaSlicer does (osteon.printed, "Skins widened under slopes"); without that rule osteon
    # read 9 % (round) and 20 % (ellipse) below the walls-and-skins W.
    assert w >= 0.92 * low
    if axis == "x":
        unwidened = osteon.analyze(v, f, sk, interval=1.0, print_profile=FDM(
            infill=0.15, skin_growth_lines=0)).section_modulus[i]
        assert unwidened < 0.92 * low  # the rule is what brings it into the band


def test_skins_are_widened_only_where_they_are_narrow():
    """A lying square bar has no slope: its skins span the layers, nothing is widened (W the
    same with and without the rule); a lying flat rhombus (17° slopes, each layer's skin strip
    0.67 mm wide) gets its skins widened: a stronger printed section, still below the walls-and-skins-solid bound of the
    solid cut."""
    def lying(profile_2d):
        v, f, sk = _bar(profile_2d, 30.0, "x")
        on = osteon.analyze(v, f, sk, interval=1.0, print_profile=FDM(infill=0.15))
        off = osteon.analyze(v, f, sk, interval=1.0,
                             print_profile=FDM(infill=0.15, skin_growth_lines=0))
        i = _middle(on, 30.0)
        return on.section_modulus[i], off.section_modulus[i], on, i
    w_on, w_off, _, _ = lying(rectangle(10.0, 10.0))
    assert w_on == w_off
    rhombus = np.array([[10.0, 0.0], [0.0, 3.0], [-10.0, 0.0], [0.0, -3.0]])
    w_on, w_off, a, i = lying(rhombus)
    assert w_off * 1.05 < w_on < a.section_solid_modulus[i]
    assert a.section_skin_area[i] > 0
