"""Stress concentration at corners (issue 33, docs/notch.md): the Kt fit, the corner finder on
stepped bars of known fillet radius, notch sensitivity, and what the results say."""

from __future__ import annotations

import itertools
import json
import math
import shutil

import numpy as np
import osteon
import pytest
from osteon import materials
from osteon.report import section_rows
from osteon.settings import Settings, engine_arguments
from shapes import revolve

D_SMALL, D_BIG = 6.0, 12.0


def stepped_bar(rho: float, d: float = D_SMALL, big: float = D_BIG, arc: int = 9,
                cone_deg: float | None = None, length: float = 30.0):
    """Closed stepped round bar along x (mm): thick x in [-15, 0], a shoulder at x = 0 with a
    fillet of radius `rho` (0: a sharp corner), thin x up to `length`. With `cone_deg` the
    shoulder is a cone at that angle to the axis instead (no fillet)."""
    xs = list(np.arange(-15.0, 0.0, 1.0))
    ts = [big / 2] * len(xs)
    if cone_deg is not None:
        run = (big - d) / 2 / math.tan(math.radians(cone_deg))
        xs += list(np.linspace(0.0, run, 6))
        ts += list(np.linspace(big / 2, d / 2, 6))
    else:
        xs.append(0.0)
        ts.append(big / 2)
        if rho > 0:
            th = np.linspace(0.0, np.pi / 2, arc)
            xs += list(rho - rho * np.cos(th))
            ts += list(d / 2 + rho - rho * np.sin(th))
        else:
            xs.append(0.0)
            ts.append(d / 2)
    tail = list(np.arange(xs[-1] + 0.5, length + 1e-9, 0.5))
    return revolve(xs + tail, ts + [d / 2] * len(tail), 96)


def bar_skeleton(length: float = 30.0):
    return osteon.Skeleton(np.array([[-15.0, 0, 0]]), np.array([[length, 0, 0]]), [-1])


def analyse(v, f, length: float = 30.0, **kw):
    return osteon.analyze(v, f, bar_skeleton(length), force=1.0, root=0, **kw)


# --- the fit -------------------------------------------------------------------------------


def tipton_kt(step, rel_r):
    """Tipton, Sorem & Rolovic (ASME J. Mech. Design 118, 1996), the FEM fit for a filleted
    shaft in bending, transcribed independently of the engine (docs/notch.md, "Kt")."""
    a = -0.14 - 0.363 * step**2 + 0.503 * step**4
    b = 1 - 2.39 * step**2 + 3.368 * step**4
    return 0.632 + 0.377 * step**-4.4 + math.sqrt(a / b) / math.sqrt(rel_r)


def test_kt_fit_reads_the_charts_at_the_issue_case():
    # Peterson's chart (stepped shaft, bending) at D/d = 2, r/d = 0.1 reads Kt ~ 1.75; the issue
    # quotes 1.73 from the charts, the Roark Table 17.1 fit gives 1.79, Tipton et al.'s FEM fit
    # 1.84, which governs (the larger).
    kt = osteon.shoulder_fillet_kt(12.0, 6.0, 0.6)
    assert 1.73 <= kt <= 1.85
    assert kt == pytest.approx(tipton_kt(2.0, 0.1), rel=1e-9)


def test_kt_at_sharp_fillets_is_tipton_sorem_rolovic_fem_fit():
    # Sharp fillets (r/d 0.01-0.04), where the photoelastic charts (Roark's fit) read low
    # against FEM: the engine returns Tipton et al.'s FEM fit, e.g. 3.32 at D/d 2, r/d 0.02
    # (Roark's fit with its Neuber continuation, main's rule, gives 3.13 there).
    for step, rel_r in itertools.product((1.2, 1.5, 2.0, 3.0), (0.01, 0.02, 0.03, 0.04)):
        got = osteon.shoulder_fillet_kt(step * 6.0, 6.0, rel_r * 6.0)
        assert got == pytest.approx(tipton_kt(step, rel_r), rel=1e-9), (step, rel_r)
    assert osteon.shoulder_fillet_kt(12.0, 6.0, 0.12) == pytest.approx(3.318, abs=1e-3)
    # Blunt fillets: Roark's fit is the larger there and governs (D/d 2, r/d 0.3: 1.40, the
    # chart's value, against Tipton et al.'s 1.34).
    blunt = osteon.shoulder_fillet_kt(12.0, 6.0, 1.8)
    assert blunt == pytest.approx(1.402, abs=1e-3)
    assert blunt > tipton_kt(2.0, 0.3) + 0.05
    # No step, no concentration: the FEM fit goes to 1.009 as D -> d (a = 0 at D = d).
    assert tipton_kt(1.0, 0.02) == pytest.approx(1.009, abs=1e-3)


def test_kt_fit_behaves_like_a_stress_concentration():
    kt = osteon.shoulder_fillet_kt
    radii = [0.12, 0.3, 0.6, 1.2, 1.8]
    assert all(kt(12, 6, a) > kt(12, 6, b) for a, b in itertools.pairwise(radii))  # sharper: up
    assert kt(6.0, 6.0, 0.6) == 1.0  # no step
    assert kt(7.2, 6.0, 0.6) < kt(9.0, 6.0, 0.6) < kt(12.0, 6.0, 0.6)  # a bigger step: higher
    assert kt(30.0, 6.0, 0.6) == kt(18.0, 6.0, 0.6)  # D/d capped at 3
    # below the fit's range (h/r < 0.25) the value at its edge (safe side: Kt grows with h/r)
    assert kt(6.6, 6.0, 2.0) == pytest.approx(kt(6.6, 6.0, 1.2))
    # sharper than Roark's range (h/r > 20): at least Neuber's sqrt law from the edge (h/r 4x:
    # Kt - 1 2x), and Tipton et al.'s FEM fit where that is larger (here: D/d 3, r/d 0.0125)
    edge, sharp = kt(18.0, 6.0, 0.3), kt(18.0, 6.0, 0.3 / 4)
    assert sharp >= 1 + (edge - 1) * 2.0
    assert sharp == pytest.approx(tipton_kt(3.0, 0.0125), rel=1e-9)
    with pytest.raises(ValueError, match="radius"):
        kt(12.0, 6.0, 0.0)
    with pytest.raises(ValueError, match="small_diameter"):
        kt(12.0, float("nan"), 0.6)


# --- the corner finder ---------------------------------------------------------------------


@pytest.mark.parametrize("rho", [1.2, 0.6])
def test_the_corner_finder_measures_a_known_fillet(rho):
    v, f = stepped_bar(rho)
    a = analyse(v, f, min_notch_radius=0.05)
    (i,) = np.flatnonzero(a.notch)  # one section, on the thin side next to the shoulder
    assert a.section_param[i] > 15.0  # thin side (the shoulder is 15 mm from the head)
    assert a.notch_radius[i] == pytest.approx(rho, rel=0.03)
    assert a.notch_step[i] == pytest.approx(2.0, rel=0.02)
    d = 2 * math.sqrt(a.section_area[i] / math.pi)  # the thin section's equivalent diameter
    assert d == pytest.approx(D_SMALL, rel=0.01)
    assert a.stress_concentration[i] == pytest.approx(
        osteon.shoulder_fillet_kt(a.notch_step[i] * d, d, a.notch_radius[i]))
    # the governing stress is Kt x the beam stress at the corner (a longer arm than the plane's)
    assert a.stress[i] >= a.stress_concentration[i] * a.nominal_stress[i]
    assert a.stress[i] <= a.stress_concentration[i] * a.nominal_stress[i] * 1.1
    others = np.ones(a.num_sections, bool)
    others[i] = False
    assert np.all(a.stress_concentration[others] == 1.0)
    assert np.all(np.isnan(a.notch_radius[others]))
    assert np.array_equal(a.stress[others], a.nominal_stress[others], equal_nan=True)


@pytest.mark.parametrize("rho", [0.12, 0.06])
def test_a_narrow_fillet_the_mesh_resolves_is_a_fillet_and_a_ring_is_a_sharp_edge(rho):
    # 0.12 and 0.06 mm fillets on d = 6 (r/d 0.02, 0.01), 9 vertices over the arc: their points
    # spread axially by 0.035 / 0.018 mm, under 0.02 r = 0.06 mm (the sharp-edge tolerance that
    # read the study's 0.12 mm fillet as a sharp edge, Kt 7.7), but far above 0.05 of the mesh's
    # edge length there: the radius is measured (docs/notch.md).
    a = analyse(*stepped_bar(rho), min_notch_radius=0.01)
    (i,) = np.flatnonzero(a.notch)
    assert a.notch_radius[i] == pytest.approx(rho, rel=0.03)
    # The same bar with a sharp edge (one ring of vertices) still reads radius 0, i.e. the clamp.
    a = analyse(*stepped_bar(0.0), min_notch_radius=0.01)
    (i,) = np.flatnonzero(a.notch)
    assert a.notch_radius[i] == 0.01


def test_a_sharp_edge_that_wanders_along_the_axis_is_still_a_sharp_edge():
    # A sharp step whose edge ring waves +-0.05 mm along the axis (8 waves around; a shoulder
    # that is not quite flat), meshed finely along the meridian near it (rings 0.25 mm apart):
    # its points spread axially by 0.035 mm, over 0.1 of the edge length, like a narrow fillet's,
    # but not radially (all at t = 3 mm): one ring, a sharp edge (docs/notch.md).
    xs, ts = list(np.arange(-15.0, 0.0, 1.0)), [6.0] * 15
    face = np.arange(6.0, 3.0 - 1e-9, -0.25)  # the shoulder face down to the edge at t = 3
    near = np.arange(0.25, 2.0, 0.25)
    tail = np.arange(2.0, 30.0 + 1e-9, 0.5)
    xs += [0.0] * len(face) + list(near) + list(tail)
    ts += list(face) + [3.0] * (len(near) + len(tail))
    v, f = revolve(xs, ts, 96)
    edge = 15 + len(face) - 1  # the profile index of the edge ring
    v[96 * edge:96 * (edge + 1), 0] += 0.05 * np.sin(8 * np.linspace(0, 2 * np.pi, 96, endpoint=False))
    a = analyse(v, f, min_notch_radius=0.01)
    (i,) = np.flatnonzero(a.notch)
    assert a.notch_radius[i] == 0.01  # radius 0, clamped


def test_a_sharp_corner_is_taken_at_the_print_resolution():
    v, f = stepped_bar(0.0)
    a = analyse(v, f)
    (i,) = np.flatnonzero(a.notch)
    assert a.notch_radius[i] == 0.2  # the default: half a 0.4 mm nozzle's line
    b = analyse(v, f, min_notch_radius=0.5)
    assert b.notch_radius[i] == 0.5
    assert b.stress_concentration[i] == pytest.approx(osteon.shoulder_fillet_kt(12, 6, 0.5), rel=1e-3)
    assert b.stress[i] < a.stress[i]  # a rounder corner: a lower peak


def test_a_plain_bar_and_a_shallow_taper_have_no_corner():
    for v, f in (revolve(np.arange(-15.0, 30.01, 0.5), np.full(91, 3.0), 96),
                 stepped_bar(0.0, cone_deg=30.0)):
        a = analyse(v, f)
        assert not a.notch.any()
        assert np.all(a.stress_concentration == 1.0)
        assert np.array_equal(a.stress, a.nominal_stress, equal_nan=True)


def test_a_stub_as_thick_as_the_model_is_the_body_not_a_shaft():
    # D/d 1.2 with a sharp step: the thin side (r 3 mm) is at least 0.4 of the model's largest
    # section (r 3.6 mm). As a shaft loaded 30 mm away (the study's bars) it is searched and
    # carries the shoulder's Kt; as a stub loaded within two of its diameters (8 mm long) it is
    # the body itself, not a shaft entering one: no search, no Kt (docs/notch.md "Cost").
    shaft = analyse(*stepped_bar(0.0, big=7.2))
    (i,) = np.flatnonzero(shaft.notch)
    assert shaft.notch_step[i] == pytest.approx(1.2, rel=0.02)
    assert shaft.stress_concentration[i] > 2.0
    stub = analyse(*stepped_bar(0.0, big=7.2, length=8.0), length=8.0)
    assert not stub.notch.any()
    assert np.all(stub.stress_concentration == 1.0)
    # the thick side alone beside it is no step: the stub's cut radii step by 1.2 as the shaft's
    cut = np.sqrt(np.asarray(stub.section_cut_area) / np.pi)
    assert np.nanmax(cut) / np.nanmin(cut[cut > 0]) == pytest.approx(1.2, rel=0.02)


def test_a_plane_inside_the_fillet_refers_kt_to_the_thin_diameter():
    # D/d 3 with a 1.8 mm fillet (round 2's D/d 3, r/d 0.3): the plane at x = 1 cuts the fillet
    # (its section 6.39 mm across, the thin part 6), so its own beam stress is ~15 % under the
    # thin part's. Kt's nominal stress is the thin diameter's where the fillet meets the thin
    # side (x = 1.8): the governing stress is Kt F (30 - 1.8) / (pi d^3 / 32), d = 6
    # (docs/notch.md, "A plane inside the fillet"). With q = 0 the plane's own beam stress.
    v, f = stepped_bar(1.8, big=18.0)
    a = analyse(v, f, min_notch_radius=0.01)
    (i,) = np.flatnonzero(a.notch)
    assert 2 * math.sqrt(a.section_area[i] / math.pi) > 6.3  # the plane is inside the fillet
    thin_nominal = 1.0 * (30.0 - 1.8) / (math.pi * D_SMALL**3 / 32)
    assert a.stress[i] == pytest.approx(a.stress_concentration[i] * thin_nominal, rel=0.02)
    assert a.nominal_stress[i] < 0.9 * thin_nominal  # before this rule, Kt x that: -15 %
    q0 = analyse(v, f, min_notch_radius=0.01, notch_sensitivity=0.0)
    assert q0.stress[i] == pytest.approx(q0.nominal_stress[i])


def test_the_plane_in_fillet_rule_keeps_the_corrected_cheburashka_converging(data_dir):
    # With the corner model on (q = 1), the cheburashka's hand (bone_3, s41: a plane inside a
    # large fillet, the hand bulging beyond it) once made the loop stop: the line through the
    # next two sections, tipped by the bulge, carried the thin radius 8 % down and let it jump
    # between rounds. The thin radius is never below the next section's (docs/notch.md).
    from rigged_models import load

    v, f, sk, w = load("cheburashka", height_mm=120.0)
    before = osteon.analyze(v, f, sk, w, force=20.0)
    allowable = before.max_stress / 2
    fix = osteon.correct(v, f, sk, w, force=20.0, allowable_stress=allowable)
    assert "bone_3" not in fix.reason  # the plane-in-fillet section is not what stops it
    if not fix.converged:
        # The loop's documented stop for a corner at a joint ("does not thicken it", as the
        # elephant's in test_correction.py), one section left weak. Since round 4's Kt (Tipton
        # et al.'s FEM fit at sharp fillets) the crease at the root of bone_0 ended 0.04 % over
        # the allowable; since round 6's acute-corner Kt (docs/notch.md) a crease at bone_1's
        # joint (14 mm: Kt 7.92 at the 0.2 mm clamp, an acute opening) stops it 2.2 x over.
        assert "does not thicken it" in fix.reason and "a corner at a joint" in fix.reason
        assert int(fix.after.weak.sum()) == 1


def test_notch_sensitivity_scales_the_peak_and_drives_weak_and_culled():
    v, f = stepped_bar(0.6)
    q1, q0, qh = (analyse(v, f, notch_sensitivity=q) for q in (1.0, 0.0, 0.5))
    (i,) = np.flatnonzero(q1.notch)
    kt = q1.stress_concentration[i]
    arm_ratio = q0.stress[i] / q0.nominal_stress[i]  # q = 0: the beam stress at the corner
    assert q1.stress[i] / q1.nominal_stress[i] == pytest.approx(kt * arm_ratio)
    assert qh.stress[i] / qh.nominal_stress[i] == pytest.approx((1 + 0.5 * (kt - 1)) * arm_ratio)
    # an allowable between the beam stress and the peak: weak only with the corner counted
    allow = 0.5 * (q1.nominal_stress[i] + q1.stress[i])
    a = analyse(v, f, allowable_stress=allow)
    assert a.weak[i] and not a.culled[i]
    assert np.all(a.stress[a.culled] <= a.section_allowable[a.culled])
    with pytest.raises(ValueError, match="notch_sensitivity"):
        analyse(v, f, notch_sensitivity=1.5)
    with pytest.raises(ValueError, match="min_notch_radius"):
        analyse(v, f, min_notch_radius=0.0)


def test_the_reason_and_the_report_say_it():
    v, f = stepped_bar(0.6)
    a = analyse(v, f)
    (i,) = np.flatnonzero(a.notch)
    reason = a.flag_reasons(i)[a.flag_names(i).index("notch")]
    assert "corner radius 0.6 mm" in reason and "× the beam stress" in reason
    row = section_rows(a, ["bar"])[i]
    assert row["stress_concentration"] == pytest.approx(a.stress_concentration[i])
    assert row["notch_radius_mm"] == pytest.approx(0.6, rel=0.03)
    assert row["nominal_stress_mpa"] < row["stress_mpa"]
    assert "notch" in row["flags"]
    json.dumps(row)  # finite numbers or null only
    assert section_rows(a, ["bar"])[0]["notch_radius_mm"] is None


# --- materials and front ends ----------------------------------------------------------------


def test_every_material_carries_its_notch_sensitivity_with_a_source():
    for m in materials.MATERIALS:
        assert 0.0 <= m.notch_sensitivity <= 1.0 and m.notch_sensitivity_source
        assert m.min_notch_radius_mm > 0 and m.min_notch_radius_source
    assert materials.get("PLA").notch_sensitivity == 1.0  # brittle (< 5 % at break)
    assert materials.get("RESIN").notch_sensitivity == 1.0
    assert materials.get("PETG").notch_sensitivity < 1.0


def test_the_front_ends_pass_the_materials_q():
    kw = engine_arguments(Settings(force_n=20, interval_mm=2, material="PETG"), ["b"])
    assert kw["notch_sensitivity"] == materials.get("PETG").notch_sensitivity
    assert kw["min_notch_radius"] == materials.get("PETG").min_notch_radius_mm
    kw = engine_arguments(Settings(force_n=20, interval_mm=2, material="PETG",
                                   notch_sensitivity=1.0, min_notch_radius_mm=0.4), ["b"])
    assert (kw["notch_sensitivity"], kw["min_notch_radius"]) == (1.0, 0.4)
    with pytest.raises(ValueError, match="notch sensitivity"):
        engine_arguments(Settings(force_n=20, interval_mm=2, notch_sensitivity=2.0), ["b"])


def test_the_cli_takes_notch_options():
    from osteon.cli.common import check, settings_from_args
    from osteon.cli.parser import build_parser

    args = build_parser().parse_args(["analyze", "m.obj", "--notch-sensitivity", "0.3",
                                      "--min-notch-radius", "0.4"])
    s = settings_from_args(args)
    assert (s.notch_sensitivity, s.min_notch_radius_mm) == (0.3, 0.4)
    args = build_parser().parse_args(["analyze", "m.obj", "--notch-sensitivity", "3"])
    with pytest.raises(ValueError, match="--notch-sensitivity"):
        check(settings_from_args(args))


# --- against FEM (one shape of the pre-registered study, coarse) -----------------------------


@pytest.mark.slow
def test_one_stepped_bar_against_fem(tmp_path):
    """D/d = 2, r/d = 0.3 (scripts/study_notch.py), elements r/2 on the fillet: osteon's
    governing stress at the fillet within the study's band of FEM's peak (-10 % .. +15 %)."""
    pytest.importorskip("gmsh")
    if shutil.which("ccx") is None:
        pytest.skip("CalculiX (ccx) not installed")
    import stepped_bars as stepped

    fem, _ = stepped.fem_peak(2.0, 0.3, 2, str(tmp_path))
    ost, radius, _, _ = stepped.osteon_peak(2.0, 0.3)
    assert radius == pytest.approx(0.3 * D_SMALL, rel=0.15)
    assert -0.10 <= (ost - fem) / fem <= 0.15


def acute_bar(rho: float, opening_deg: float, d: float = D_SMALL, big: float = D_BIG,
              arc: int = 13, length: float = 30.0):
    """A stepped round bar along x whose shoulder is a cone opening `opening_deg` from the thin
    side (90: the flat shoulder; 45: a cup around the thin bar, an acute corner as at a tail's
    root), the corner filleted with radius `rho` (a circle tangent to the thin side and the cone).
    Thick x in [-15, lip], the cone from (lip, D/2) down to the corner at (0, d/2)."""
    a = math.radians(opening_deg)
    lip = (big - d) / 2 / math.tan(a)
    xs = list(np.arange(-15.0, lip, 1.0)) + [lip]
    ts = [big / 2] * len(xs)
    xc, tc = rho / math.tan(a / 2), d / 2 + rho  # the fillet's centre
    start = (xc - rho * math.sin(a), tc + rho * math.cos(a))  # where it meets the cone
    for s in np.linspace(0.0, 1.0, 6)[1:-1]:  # the cone's flank
        xs.append(lip + (start[0] - lip) * s)
        ts.append(big / 2 + (start[1] - big / 2) * s)
    for phi in np.linspace(math.pi / 2 + a, 1.5 * math.pi, arc):  # the fillet
        xs.append(xc + rho * math.cos(phi))
        ts.append(tc + rho * math.sin(phi))
    tail = list(np.arange(xs[-1] + 0.5, length + 1e-9, 0.5))
    return revolve(xs + tail, ts + [d / 2] * len(tail), 96)


@pytest.mark.parametrize(("opening", "factor"), [(45.0, 2.52), (60.0, 2.29)])
def test_an_acute_corner_raises_kt_by_the_fem_factor_of_its_opening(opening, factor):
    # Round 6 (docs/notch.md): at an acute corner CalculiX's Kt - 1 is 2.52 x the stepped bar's
    # at 45 degrees and 2.29 x at 60 (a junction tilted 45 and 30 degrees, its acute side). A
    # revolved cup around the thin bar opens exactly that angle: the same fillet reads the same
    # radius as on a flat shoulder, and its Kt - 1 is raised by that factor.
    rho = 0.6
    v, f = acute_bar(rho, opening)
    a = analyse(v, f, min_notch_radius=0.01)
    flagged = np.flatnonzero(a.stress_concentration > 1)
    assert len(flagged) >= 1
    i = flagged[np.argmax(a.stress[flagged])]
    assert a.notch_radius[i] == pytest.approx(rho, rel=0.1)
    d = 2 * math.sqrt(a.section_area[i] / math.pi)
    bar = osteon.shoulder_fillet_kt(a.notch_step[i] * d, d, a.notch_radius[i])
    assert (a.stress_concentration[i] - 1) / (bar - 1) == pytest.approx(factor, rel=0.03)
    # the flat shoulder with the same fillet: the stepped bar's Kt, no factor
    v, f = acute_bar(rho, 90.0)
    b = analyse(v, f, min_notch_radius=0.01)
    j = int(np.argmax(b.stress_concentration))
    d = 2 * math.sqrt(b.section_area[j] / math.pi)
    assert b.stress_concentration[j] == pytest.approx(
        osteon.shoulder_fillet_kt(b.notch_step[j] * d, d, b.notch_radius[j]))
