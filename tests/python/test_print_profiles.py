"""Print profiles (issue 31): the presets and their sources, the settings -> engine mapping,
the CLI and batch options, the JSON report. The printed section itself (walls, skins, infill)
is the engine's (test_printed_profile_sections / print-core); here: that every front end
reaches it, once. Meshes generated here (a round rod), no shared data."""

from __future__ import annotations

import json

import numpy as np
import pytest
from osteon import materials, profiles
from osteon.batch.settings import BatchSettings
from osteon.cli import main
from osteon.io import write_mesh, write_tgf
from osteon.settings import Settings, engine_arguments
from shapes import cylinder_along

# --------------------------------------------------------------------------- presets


def test_presets_are_checked_profiles_with_sources():
    presets = profiles.print_profiles()
    assert {"prusaslicer", "bambustudio", "cura", "resin_hollow", "solid"} <= set(presets)
    for key, p in presets.items():
        assert isinstance(p, profiles.PrintProfile), key
        assert p.name and len(p.source) > 20, key
        # as checked as a hand-made one: the class methods rebuild it unchanged
        assert p.with_changes() == p and profiles.PrintProfile.from_dict(p.as_dict()) == p
        assert profiles.get_profile(key.upper()) == p
    fdm = [p for p in presets.values() if p.kind == "fdm"]
    assert len(fdm) == 3
    for p in fdm:  # a 0.4 mm nozzle at 0.2 mm layers (the comparison point)
        assert 0.4 <= p.line_width <= 0.45 and p.layer_height == 0.2
        assert p.perimeters == 2 and 0.15 <= p.infill <= 0.20 and p.pattern in profiles.PATTERNS
        assert p.top_bottom_layers >= 3 and not p.is_solid
    # each number is quoted with its key in the source
    assert "perimeters = 2" in presets["prusaslicer"].source
    assert "wall_loops = 2" in presets["bambustudio"].source
    assert "wall_line_count" in presets["cura"].source
    assert presets["resin_hollow"].kind == "resin_hollow" and presets["resin_hollow"].shell == 2
    assert presets["solid"].is_solid


def test_every_material_suggests_a_preset_of_its_process():
    presets = profiles.print_profiles()
    kind = {"FDM": "fdm", "resin": "resin_hollow", "SLS": "solid"}
    for m in materials.MATERIALS:
        assert presets[m.default_profile].kind == kind[m.process], m.key
    assert materials.get("PLA").default_profile == "prusaslicer"


# --------------------------------------------------------------------------- settings


def test_settings_resolve_the_profile_and_its_overrides():
    s = Settings(force_n=20, interval_mm=2, print_profile="prusaslicer", perimeters=3,
                 infill=0.4, infill_pattern="grid")
    p = s.profile()
    base = profiles.get_profile("prusaslicer")
    assert (p.perimeters, p.infill, p.pattern) == (3, 0.4, "grid")
    assert (p.line_width, p.layer_height, p.top_bottom_layers) == (
        base.line_width, base.layer_height, base.top_bottom_layers)
    assert "perimeters 3" in p.name and p.source == base.source
    assert Settings(force_n=20, interval_mm=2, print_profile="resin_hollow",
                    shell_mm=3.0).profile().shell == 3.0
    assert Settings(force_n=20, interval_mm=2).profile() == profiles.PrintProfile.solid()


@pytest.mark.parametrize("kw,match", [
    ({"perimeters": 3}, "perimeters needs an FDM profile"),  # solid has no perimeters
    ({"print_profile": "prusaslicer", "shell_mm": 2.0}, "shell_mm needs a resin profile"),
    ({"print_profile": "prusaslicer", "perimeters": 2.5}, "perimeters must be a whole"),
    ({"print_profile": "cura", "line_width_mm": 0.0}, "line_width must be"),
    ({"print_profile": "cura", "infill": 1.5}, "infill must be a fraction"),
    ({"print_profile": "cura", "infill_pattern": "zigzag"}, "unknown infill pattern"),
    ({"print_profile": "makerbot"}, "unknown print profile"),
])
def test_bad_print_settings_name_the_problem(kw, match):
    with pytest.raises(ValueError, match=match):
        engine_arguments(Settings(force_n=20, interval_mm=2, **kw), [])


def test_solid_passes_no_argument_to_the_engine():
    # solid: today's call, bit for bit (the engine's own default)
    kw = engine_arguments(Settings(force_n=20, interval_mm=2), [])
    assert "print_profile" not in kw
    s = Settings(force_n=20, interval_mm=2, print_profile="prusaslicer")
    assert engine_arguments(s, [])["print_profile"] == profiles.get_profile("prusaslicer")


def test_batch_settings_round_trip_the_profile():
    b = BatchSettings.from_any({"print_profile": "cura", "perimeters": 3, "infill": 0.1})
    assert b.settings.profile().perimeters == 3 and b.settings.profile().infill == 0.1
    d = b.as_dict()["settings"]
    assert d["print_profile"] == "cura" and d["perimeters"] == 3
    again = BatchSettings.from_any(d)
    assert again.settings.profile() == b.settings.profile()
    with pytest.raises(ValueError, match="unknown batch setting"):
        BatchSettings.from_any({"print_profil": "cura"})


# --------------------------------------------------------------------------- CLI


@pytest.fixture
def rod_files(tmp_path):
    """A horizontal cantilever rod along x (r = 5 mm, 60 mm) with a one-bone TGF skeleton."""
    v, f = cylinder_along([0, 0, 0], [60, 0, 0], 5.0)
    obj = tmp_path / "rod.obj"
    write_mesh(obj, v, f)
    write_tgf(tmp_path / "rod.tgf", np.array([[0, 0, 0], [60, 0, 0.0]]), np.array([[0, 1]]))
    return obj


def _args(obj, *extra):
    # the longest side (x: 60 mm + the caps) kept: 1 file unit = 1 mm
    return ["analyze", str(obj), "--height-mm", "60", "--force", "10", "-q", *extra]


def test_cli_batch_parse_print_options():
    from osteon.cli import build_parser
    from osteon.cli.common import settings_from_args

    p = build_parser()
    args = p.parse_args(["analyze", "m.obj", "--profile", "bambustudio", "--perimeters", "4",
                         "--infill", "25%", "--infill-pattern", "gyroid", "--line-width",
                         "0.5", "--layer-height", "0.3", "--top-bottom-layers", "6"])
    s = settings_from_args(args)
    assert (s.print_profile, s.perimeters, s.infill, s.infill_pattern) == (
        "bambustudio", 4, 0.25, "gyroid")
    pr = s.profile()
    assert (pr.line_width, pr.layer_height, pr.top_bottom_layers) == (0.5, 0.3, 6)
    args = p.parse_args(["batch", "lib", "--out", "o", "--profile", "resin_hollow", "--shell",
                         "3"])
    assert settings_from_args(args).profile().shell == 3.0  # batch: the same options
    assert p.parse_args(["analyze", "m.obj"]).profile == "solid"  # the default: solid


@pytest.mark.parametrize("extra,needle", [
    (["--infill", "0.15"], "--infill"),  # a percentage: 0.15 would be 0.15 %
    (["--infill", "150"], "--infill"),
    (["--profile", "makerbot"], "--profile"),
    (["--perimeters", "3"], "--perimeters: perimeters needs an FDM profile"),
    (["--profile", "prusaslicer", "--shell", "2"], "--shell"),
    (["--profile", "cura", "--perimeters", "-1"], "--perimeters"),
    (["--profile", "cura", "--line-width", "0"], "--line-width"),
    (["--profile", "cura", "--layer-height", "-0.2"], "--layer-height"),
    (["--profile", "cura", "--top-bottom-layers", "-2"], "--top-bottom-layers"),
])
def test_bad_print_flags_give_one_line(rod_files, extra, needle, capsys):
    try:
        rc = main(_args(rod_files, *extra))
    except SystemExit as e:  # argparse's own check (choices, type): usage + one error line
        rc = e.code
    err = capsys.readouterr().err
    assert rc == 2 and needle in err and "Traceback" not in err
    errors = [line for line in err.strip().splitlines() if "error:" in line]
    assert len(errors) == 1


def test_validate_fem_refuses_a_printed_profile(rod_files, capsys):
    rc = main(["validate", str(rod_files), "--fem", "--profile", "cura", "-q"])
    err = capsys.readouterr().err
    assert rc == 2 and "--fem checks the solid part" in err and len(err.strip().splitlines()) == 1


def test_list_profiles_names_every_preset_and_its_source(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--list-profiles"])
    assert e.value.code == 0
    out = capsys.readouterr().out
    for key, p in profiles.print_profiles().items():
        assert key in out and p.source[:40] in out
    with pytest.raises(SystemExit):
        main(["analyze", "--help"])
    assert "--profile" in capsys.readouterr().out


def test_report_echoes_the_solid_profile(rod_files, tmp_path):
    js = tmp_path / "solid.json"
    assert main(_args(rod_files, "--json", str(js))) == 0
    rep = json.loads(js.read_text())
    assert rep["schema_version"] == 2
    assert rep["print_profile"] == profiles.PrintProfile.solid().as_dict()
    assert rep["settings"]["print_profile"] == "solid"
    rows = [r for r in rep["section_table"] if r["modulus_mm3"] is not None]
    assert rows and all(r["solid_modulus_mm3"] == r["modulus_mm3"] for r in rows)


@pytest.mark.parametrize("extra", [["--profile", "prusaslicer", "--infill", "0"],
                                   ["--profile", "resin_hollow", "--shell", "1"]])
def test_profile_flags_reach_the_engine(rod_files, tmp_path, extra):
    """A printed rod is weaker than a solid one: its printed W is at most the solid W, so
    its peak stress is at least the solid's; the report carries the profile and the areas."""
    solid, printed = tmp_path / "s.json", tmp_path / "p.json"
    assert main(_args(rod_files, "--json", str(solid))) == 0
    assert main(_args(rod_files, *extra, "--json", str(printed))) == 0
    s, p = json.loads(solid.read_text()), json.loads(printed.read_text())
    assert p["print_profile"]["kind"] == ("fdm" if "prusaslicer" in extra else "resin_hollow")
    assert p["print_profile"]["infill" if "prusaslicer" in extra else "shell"] in (0.0, 1.0)
    # r = 5 mm, lying: 2 walls of 0.45 mm at the sides, 4 × 0.2 mm skins, no infill -> the
    # printed W clearly below the solid W (0.43 of it by the slicer measurement)
    assert p["max_stress_mpa"] > 1.2 * s["max_stress_mpa"]
    rows = [r for r in p["section_table"] if r["modulus_mm3"] is not None]
    assert all(r["modulus_mm3"] <= r["solid_modulus_mm3"] * (1 + 1e-9) for r in rows)
    assert all(r["wall_area_mm2"] is not None and r["wall_area_mm2"] > 0 for r in rows)


def test_terminal_and_correction_follow_the_profile(rod_files, tmp_path, capsys):
    """The terminal says how the sections were counted; ``correct`` with a profile thickens
    the printed rod more than the solid one (its walls-and-skins W is the smaller)."""
    def loud(*extra):  # without -q
        return [a for a in _args(rod_files, *extra) if a != "-q"]

    assert main(loud()) == 0
    assert "sections as cut (solid)" in capsys.readouterr().out
    assert main(loud("--profile", "prusaslicer")) == 0
    assert "sections as printed: PrusaSlicer" in capsys.readouterr().out
    scales = {}
    for name, extra in (("solid", []), ("printed", ["--profile", "prusaslicer", "--infill", "0"])):
        js, out = tmp_path / f"{name}.json", tmp_path / f"{name}.obj"
        argv = ["correct", str(rod_files), "--height-mm", "60", "--force", "60", "-q",
                "--strength-mpa", "40", "--json", str(js), "--out", str(out), *extra]
        assert main(argv) == 0
        rep = json.loads(js.read_text())
        assert rep["converged"] and rep["max_stress_before_mpa"] > rep["allowable_stress_mpa"]
        scales[name] = rep["bone_scale"][0]
    assert scales["printed"] > scales["solid"] > 1.0


def test_the_report_states_the_corner_radius_the_engine_was_given():
    """An FDM profile sets the smallest corner to half its line width (docs/notch.md): the
    report's settings say the radius engine_arguments passed, not the material's."""
    s = Settings(force_n=20, interval_mm=2, print_profile="prusaslicer")
    given = engine_arguments(s, [])["min_notch_radius"]
    assert given == pytest.approx(0.5 * profiles.get_profile("prusaslicer").line_width)
    assert s.as_dict()["min_notch_radius_mm"] == pytest.approx(given)
