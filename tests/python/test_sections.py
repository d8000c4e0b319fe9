"""Section properties against closed forms (docs/method.md, Section properties and stress): exact polygon integrals, minimum section
modulus over all bending directions with unsymmetric bending."""

import numpy as np
import osteon
import pytest
from shapes import circle, l_section, rectangle


def rel(a, b):
    return abs(a - b) / abs(b)


def test_circle_modulus_pi_r3_over_4():
    r = 5.0
    p = osteon.section_properties(circle(r, 2048))
    assert rel(p["area"], np.pi * r**2) < 1e-5
    assert rel(p["modulus"], np.pi * r**3 / 4) < 0.005


def test_square_weakest_direction_is_the_diagonal():
    a = 10.0
    p = osteon.section_properties(rectangle(a, a))
    # edge direction would give a^3/6; the diagonal gives a^3/(6 sqrt 2)
    assert rel(p["modulus"], a**3 / (6 * np.sqrt(2))) < 1e-12
    assert p["modulus"] < a**3 / 6 * 0.75


@pytest.mark.parametrize("b,h", [(20.0, 5.0), (8.0, 3.0), (40.0, 1.0)])
def test_rectangle_modulus(b, h):
    p = osteon.section_properties(rectangle(b, h))
    expected = b**2 * h**2 / (6 * np.sqrt(b**2 + h**2))
    assert rel(p["modulus"], expected) < 1e-12
    # a little below the thin-direction value b h^2 / 6; flat parts are weak across
    assert p["modulus"] < b * h**2 / 6


def test_rotation_and_translation_do_not_change_modulus():
    base = osteon.section_properties(rectangle(12.0, 4.0))["modulus"]
    t = 0.7
    rot = np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
    moved = rectangle(12.0, 4.0) @ rot.T + [250.0, -90.0]
    assert rel(osteon.section_properties(moved)["modulus"], base) < 1e-9


def test_tube_modulus():
    ro, ri = 6.0, 4.0
    p = osteon.section_properties(circle(ro, 2048), [circle(ri, 2048)[::-1]])
    assert rel(p["area"], np.pi * (ro**2 - ri**2)) < 1e-5
    assert rel(p["modulus"], np.pi * (ro**4 - ri**4) / (4 * ro)) < 0.005


def test_hole_orientation_does_not_matter():
    ro, ri = 6.0, 4.0
    a = osteon.section_properties(circle(ro), [circle(ri)])["modulus"]
    b = osteon.section_properties(circle(ro)[::-1], [circle(ri)[::-1]])["modulus"]
    assert rel(a, b) < 1e-12


def l_section_modulus_by_rectangles(a, b, t):
    """Independent: J from two rectangles (parallel-axis theorem), then the worst bending
    direction by sweeping 20 000 moment directions with the unsymmetric-bending stress."""
    rects = [(a / 2, t / 2, a, t), (t / 2, t + (b - t) / 2, t, b - t)]  # cx, cy, w, h
    area = sum(w * h for _, _, w, h in rects)
    cx = sum(x * w * h for x, _, w, h in rects) / area
    cy = sum(y * w * h for _, y, w, h in rects) / area
    juu = sum(w**3 * h / 12 + w * h * (x - cx) ** 2 for x, _, w, h in rects)
    jvv = sum(w * h**3 / 12 + w * h * (y - cy) ** 2 for _, y, w, h in rects)
    juv = sum(w * h * (x - cx) * (y - cy) for x, y, w, h in rects)
    jinv = np.linalg.inv(np.array([[juu, juv], [juv, jvv]]))
    corners = l_section(a, b, t) - [cx, cy]
    phi = np.linspace(0, np.pi, 20000)
    m = np.stack([np.cos(phi), np.sin(phi)], 1)
    peak = np.abs(m @ jinv @ corners.T).max(axis=1)  # peak stress per unit moment
    return 1.0 / peak.max(), area, (cx, cy)


def test_l_section_against_rectangle_decomposition():
    a, b, t = 30.0, 20.0, 4.0
    expected, area, centroid = l_section_modulus_by_rectangles(a, b, t)
    p = osteon.section_properties(l_section(a, b, t))
    assert rel(p["area"], area) < 1e-12
    assert np.allclose(p["centroid"], centroid)
    assert rel(p["modulus"], expected) < 0.005
