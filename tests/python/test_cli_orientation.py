"""``osteon analyze`` with a build direction, layer ratio and --orient (issue 18), on a generated
L-shaped rod (no shared data)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from osteon.cli import main
from osteon.io import load_model, write_mesh, write_tgf
from shapes import cylinder_along, merge


@pytest.fixture
def l_rod_files(tmp_path):
    """L rod: 60 mm along x, then 40 mm up along z (r = 4 mm), with a TGF skeleton."""
    v, f = merge(cylinder_along([0, 0, 0], [60, 0, 0], 4.0),
                 cylinder_along([60, 0, 0], [60, 0, 40], 4.0))
    obj = tmp_path / "l_rod.obj"
    write_mesh(obj, v, f)
    write_tgf(tmp_path / "l_rod.tgf", np.array([[0, 0, 0], [60, 0, 0], [60, 0, 40.0]]),
              np.array([[0, 1], [1, 2]]))
    return obj


def _args(obj, *extra):
    # The longest side (x: 0 to 60 + r = 64 mm) stays 64 mm: 1 file unit = 1 mm.
    return ["analyze", str(obj), "--height-mm", "64", "--force", "20", "--safety-factor", "1",
            *extra]


def test_layer_ratio_and_build_direction_reach_the_report(l_rod_files, tmp_path, capsys):
    iso, lay = tmp_path / "iso.json", tmp_path / "lay.json"
    assert main(_args(l_rod_files, "--strength-mpa", "60", "--json", str(iso), "-q")) == 0
    assert main(_args(l_rod_files, "--material", "PLA", "--strength-mpa", "60",
                      "--layer-ratio", "0.5", "--build-direction", "1,0,0",
                      "--json", str(lay))) == 0
    out = capsys.readouterr().out
    a, b = json.loads(iso.read_text()), json.loads(lay.read_text())
    assert a["layer_strength_ratio"] == 1.0 and b["layer_strength_ratio"] == 0.5
    assert b["build_direction"] == [1.0, 0.0, 0.0]
    assert a["max_stress_mpa"] == b["max_stress_mpa"]  # stresses do not depend on orientation
    # Built along x, the horizontal arm (all normals along x) is checked against Z = 30 MPa.
    rows = [r for r in b["section_table"] if r["bone_index"] == 0 and r["stress_mpa"]]
    inner = [r for r in rows if abs(r["normal"][0]) > 0.999]
    assert inner and all(r["allowable_mpa"] == pytest.approx(30.0) for r in inner)
    assert all(r["limit"] == "across layers" for r in inner)
    assert all(r["stress_ratio"] == pytest.approx(r["stress_mpa"] / 30.0) for r in inner)
    assert "across layers" in out


def test_material_preset_gives_its_layer_ratio(l_rod_files, tmp_path):
    js = tmp_path / "r.json"
    assert main(_args(l_rod_files, "--material", "PETG", "--json", str(js), "-q")) == 0
    assert json.loads(js.read_text())["layer_strength_ratio"] == 0.6
    assert main(_args(l_rod_files, "--material", "resin", "--json", str(js), "-q")) == 0
    assert json.loads(js.read_text())["layer_strength_ratio"] == 1.0


def test_orient_prints_candidates_and_writes_the_turned_model(l_rod_files, tmp_path, capsys):
    js, out_obj, png = tmp_path / "r.json", tmp_path / "turned.obj", tmp_path / "r.png"
    rc = main(_args(l_rod_files, "--material", "PLA", "--orient-out", str(out_obj),
                    "--orient-samples", "1000", "--json", str(js), "--png", str(png)))
    assert rc == 0
    text = capsys.readouterr().out
    assert "best print orientations" in text and "worst σ/[σ]" in text
    rep = json.loads(js.read_text())
    o = rep["orientation"]
    assert o["best"]["worst_ratio"] <= o["reference_ratio"]
    d, rot = np.array(o["best"]["direction"]), np.array(o["best"]["rotation"])
    np.testing.assert_allclose(rot @ d, [0, 0, 1], atol=1e-12)
    turned = load_model(out_obj, skeleton=l_rod_files.with_suffix(".tgf"), height_mm=None)
    src = load_model(l_rod_files, height_mm=None)
    np.testing.assert_allclose(turned.vertices, src.vertices @ rot.T, atol=1e-4)
    assert png.stat().st_size > 1000


@pytest.mark.parametrize("extra, match", [
    (["--build-direction", "0,0"], "--build-direction"),
    (["--build-direction", "0,0,0"], "--build-direction"),
    (["--layer-ratio", "0"], "--layer-ratio"),
    (["--orient", "--orient-samples", "0"], "--orient-samples"),
])
def test_bad_print_options(l_rod_files, capsys, extra, match):
    assert main(_args(l_rod_files, *extra)) != 0
    assert match in capsys.readouterr().err
