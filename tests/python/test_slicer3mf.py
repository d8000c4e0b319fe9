"""The slicer project (osteon.slicer3mf): sliced by the real PrusaSlicer (Debian's
``prusa-slicer`` CLI) and its G-code read back, and the Bambu Studio / OrcaSlicer file checked
for the structure their reader (bbs_3mf.cpp) expects. Meshes made here."""

from __future__ import annotations

import itertools
import shutil
import subprocess
import xml.etree.ElementTree as ET
import zipfile

import gcode
import numpy as np
import pytest
from osteon.profiles import PrintProfile
from osteon.reinforcement import convex_volume
from osteon.settings import engine_takes_print_profile
from osteon.slicer3mf import BED_CENTER, build_rotation, write_3mf
from shapes import circle, prism

NS = "{http://schemas.microsoft.com/3dmanufacturing/core/2015/02}"
PROFILE = PrintProfile.fdm(perimeters=2, line_width=0.45, layer_height=0.2, top_bottom_layers=4,
                           infill=0.15, pattern="gyroid", solid_infill_below_area=70.0)


def _rod(radius=8.0, length=24.0):
    """A round rod along +x from x = 0 to ``length`` (printed standing: build direction +x)."""
    return prism(circle(radius, 96), length)


def _band(radius, x0, x1):
    """A closed modifier around the rod from x0 to x1 (the hull of two circles, 1 mm out)."""
    ring = np.column_stack([np.zeros(48), circle(radius, 48)])
    return convex_volume(np.concatenate([ring + [x0, 0, 0], ring + [x1, 0, 0]]), 1.0)


def _regions():
    walls_v, walls_f = _band(8.0, 6.0, 12.0)    # more walls: x 5..13 with the margin
    fill_v, fill_f = _band(8.0, 16.0, 20.0)     # denser infill: x 15..21
    return [{"bone": "walls", "vertices": walls_v, "faces": walls_f, "perimeters": 5,
             "infill": 0.15},
            {"bone": "infill", "vertices": fill_v, "faces": fill_f, "perimeters": 2,
             "infill": 0.40}]


@pytest.mark.skipif(shutil.which("prusa-slicer") is None,
                    reason="prusa-slicer is not installed (apt-get install prusa-slicer)")
def test_prusaslicer_prints_the_modifiers_settings(tmp_path):
    v, f = _rod()
    path = tmp_path / "rod.3mf"
    write_3mf(path, v, f, _regions(), PROFILE, build_direction=(1, 0, 0), slicer="prusaslicer")
    out = tmp_path / "rod.gcode"
    run = subprocess.run(["prusa-slicer", "--export-gcode", str(path), "-o", str(out)],
                         check=False, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    layers = gcode.layers(out)
    # PrusaSlicer's first layer is 0.35 mm; then 0.2 mm layers: z = 0.35 + 0.2 k
    assert len(layers) == pytest.approx((24.0 - 0.35) / 0.2 + 1, abs=1)

    def pick(z0, z1):
        return [layers[z] for z in layers if z0 <= z <= z1]

    walls, dense = pick(5.6, 12.4), pick(15.6, 20.4)
    plain = pick(1.6, 4.4) + pick(13.6, 14.4) + pick(21.6, 22.4)  # clear of skins and modifiers
    assert len(walls) >= 30 and len(dense) >= 20 and len(plain) >= 20
    assert [gcode.wall_loops_round(m) for m in walls] == [5] * len(walls)
    assert [gcode.wall_loops_round(m) for m in dense] == [2] * len(dense)
    assert [gcode.wall_loops_round(m) for m in plain] == [2] * len(plain)
    # Infill: the extruded sparse-infill area per layer grows with the density (40 % / 15 %);
    # the wall region's infill island is smaller (three more loops) but as sparse as outside.
    fill = np.array([gcode.extruded_area(m, "Internal infill") for m in plain])
    fill_dense = np.array([gcode.extruded_area(m, "Internal infill") for m in dense])
    assert fill.min() > 0
    ratio = fill_dense.mean() / fill.mean()
    assert 0.40 / 0.15 * 0.8 < ratio < 0.40 / 0.15 * 1.2, ratio
    # walls per layer: 2 loops outside, 5 inside (area of the wall moves ~ loops x length x w)
    wall_area = [sum(gcode.extruded_area(m, t) for t in gcode.WALL_TYPES) for m in plain]
    wall_area5 = [sum(gcode.extruded_area(m, t) for t in gcode.WALL_TYPES) for m in walls]
    assert np.mean(wall_area5) / np.mean(wall_area) > 2.0


def _read(path):
    with zipfile.ZipFile(path) as z:
        names = set(z.namelist())
        return names, {n: z.read(n) for n in names}


def test_prusaslicer_file_structure(tmp_path):
    v, f = _rod()
    regions = _regions()
    place = write_3mf(tmp_path / "p.3mf", v, f, regions, PROFILE, build_direction=(1, 0, 0))
    names, data = _read(tmp_path / "p.3mf")
    assert {"[Content_Types].xml", "_rels/.rels", "3D/3dmodel.model",
            "Metadata/Slic3r_PE_model.config"} <= names
    model = ET.fromstring(data["3D/3dmodel.model"])
    assert model.get("unit") == "millimeter"
    objs = model.findall(f"{NS}resources/{NS}object")
    assert len(objs) == 1
    xyz = np.array([[float(p.get(k)) for k in "xyz"]
                    for p in objs[0].iter(f"{NS}vertex")])
    tris = objs[0].findall(f"{NS}mesh/{NS}triangles/{NS}triangle")
    assert len(tris) == len(f) + sum(len(r["faces"]) for r in regions)
    model_xyz = xyz[:len(v)]
    # placed: the rod's axis (+x) is +z, it stands on the bed, centred on the bed
    np.testing.assert_allclose(model_xyz[:, 2].min(), 0.0, atol=1e-5)
    np.testing.assert_allclose(model_xyz[:, 2].max(), 24.0, atol=1e-4)
    lo, hi = model_xyz.min(0), model_xyz.max(0)
    np.testing.assert_allclose(0.5 * (lo + hi)[:2], BED_CENTER["prusaslicer"], atol=1e-4)
    np.testing.assert_allclose(place["rotation"] @ [1, 0, 0], [0, 0, 1], atol=1e-12)
    cfg = ET.fromstring(data["Metadata/Slic3r_PE_model.config"])
    obj = cfg.find("object")
    settings = {m.get("key"): m.get("value") for m in obj.findall("metadata")}
    assert settings["perimeters"] == "2" and settings["fill_density"] == "15%"
    assert settings["layer_height"] == "0.2" and settings["fill_pattern"] == "gyroid"
    vols = obj.findall("volume")
    assert len(vols) == 3
    ranges = [(int(x.get("firstid")), int(x.get("lastid"))) for x in vols]
    assert ranges[0] == (0, len(f) - 1)
    assert all(b[0] == a[1] + 1 for a, b in itertools.pairwise(ranges))
    assert ranges[-1][1] == len(tris) - 1
    meta = [{m.get("key"): m.get("value") for m in x.findall("metadata")} for x in vols]
    assert meta[0]["volume_type"] == "ModelPart" and "modifier" not in meta[0]
    assert meta[1]["modifier"] == "1" and meta[1]["volume_type"] == "ParameterModifier"
    assert (meta[1]["perimeters"], meta[1]["fill_density"]) == ("5", "15%")
    assert (meta[2]["perimeters"], meta[2]["fill_density"]) == ("2", "40%")


@pytest.mark.parametrize("slicer", ["bambu", "orca"])
def test_bambu_and_orca_file_structure(tmp_path, slicer):
    v, f = _rod()
    regions = _regions()
    write_3mf(tmp_path / "b.3mf", v, f, regions, PROFILE, build_direction=(1, 0, 0),
              slicer=slicer)
    names, data = _read(tmp_path / "b.3mf")
    assert {"[Content_Types].xml", "_rels/.rels", "3D/3dmodel.model",
            "Metadata/model_settings.config"} <= names
    model = ET.fromstring(data["3D/3dmodel.model"])
    objs = {o.get("id"): o for o in model.findall(f"{NS}resources/{NS}object")}
    meshes = {k: o for k, o in objs.items() if o.find(f"{NS}mesh") is not None}
    assemblies = [o for o in objs.values() if o.find(f"{NS}components") is not None]
    assert len(meshes) == 3 and len(assemblies) == 1
    comps = [c.get("objectid") for c in assemblies[0].iter(f"{NS}component")]
    assert sorted(comps) == sorted(meshes)
    items = model.findall(f"{NS}build/{NS}item")
    assert [i.get("objectid") for i in items] == [assemblies[0].get("id")]
    counts = {k: len(o.findall(f"{NS}mesh/{NS}triangles/{NS}triangle")) for k, o in meshes.items()}
    cfg = ET.fromstring(data["Metadata/model_settings.config"])
    (obj,) = cfg.findall("object")
    assert obj.get("id") == assemblies[0].get("id")
    settings = {m.get("key"): m.get("value") for m in obj.findall("metadata")}
    assert settings["wall_loops"] == "2" and settings["sparse_infill_density"] == "15%"
    parts = obj.findall("part")
    assert sorted(p.get("id") for p in parts) == sorted(meshes)
    kinds = [p.get("subtype") for p in parts]
    assert kinds == ["normal_part", "modifier_part", "modifier_part"]
    part_meta = [{m.get("key"): m.get("value") for m in p.findall("metadata")} for p in parts]
    assert counts[parts[0].get("id")] == len(f)
    assert (part_meta[1]["wall_loops"], part_meta[1]["sparse_infill_density"]) == ("5", "15%")
    assert (part_meta[2]["wall_loops"], part_meta[2]["sparse_infill_density"]) == ("2", "40%")
    assert counts[parts[1].get("id")] == len(regions[0]["faces"])


def test_build_rotation_takes_the_build_direction_up():
    for d in ([0, 0, 1], [1, 0, 0], [0, -1, 0], [1, 2, 3], [0, 0, -1], [1e-9, 0, -1]):
        r = build_rotation(d)
        np.testing.assert_allclose(r @ (np.array(d) / np.linalg.norm(d)), [0, 0, 1], atol=1e-9)
        np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-12)
        assert np.linalg.det(r) == pytest.approx(1.0)


def test_bad_input_names_the_problem(tmp_path):
    v, f = _rod()
    with pytest.raises(ValueError, match="unknown slicer"):
        write_3mf(tmp_path / "x.3mf", v, f, [], PROFILE, slicer="cura")
    with pytest.raises(ValueError, match="FDM"):
        write_3mf(tmp_path / "x.3mf", v, f, [], PrintProfile.solid())
    with pytest.raises(ValueError, match="perimeters"):
        write_3mf(tmp_path / "x.3mf", v, f, [{"vertices": v, "faces": f, "infill": 0.2}], PROFILE)
    with pytest.raises(ValueError, match="build_direction"):
        write_3mf(tmp_path / "x.3mf", v, f, [], PROFILE, build_direction=(0, 0, 0))
    assert not list(tmp_path.iterdir())  # nothing half-written


@pytest.mark.skipif(shutil.which("prusa-slicer") is None,
                    reason="prusa-slicer is not installed (apt-get install prusa-slicer)")
@pytest.mark.skipif(not engine_takes_print_profile(),
                    reason="this engine has no printed section (print_profile=)")
def test_a_reinforced_rod_prints_the_walls_osteon_asked_for(tmp_path):
    """osteon.reinforce on a standing rod r = 5 (bone z 0..40, 10 N) that needs 5 walls at the
    allowable (test_reinforce's closed form), exported and sliced: the layers inside the
    modifier have the region's walls, the others the profile's 2."""
    import osteon
    from test_reinforce import KW, _fdm, _rod, _tube_w

    v, f, sk = _rod()
    probe = osteon.analyze(v, f, sk, allowable_stress=30, print_profile=_fdm(2), **KW)
    m = np.max(np.abs(probe.moment[probe.valid]))
    allowable = 0.5 * (m / _tube_w(4) + m / _tube_w(5))
    r = osteon.reinforce(v, f, sk, allowable_stress=allowable, print_profile=_fdm(2), **KW)
    (g,) = r.regions
    assert g["perimeters"] == 5
    path = tmp_path / "rod.3mf"
    place = r.write_3mf(path)
    out = tmp_path / "rod.gcode"
    run = subprocess.run(["prusa-slicer", "--export-gcode", str(path), "-o", str(out)],
                         check=False, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    layers = gcode.layers(out)
    z0, z1 = np.asarray(g["z_range"]) + place["translation"][2]  # the modifier on the bed
    inside = [gcode.wall_loops_round(layers[z]) for z in layers if z0 + 0.5 <= z <= z1 - 0.5]
    outside = [gcode.wall_loops_round(layers[z]) for z in layers
               if z1 + 0.5 <= z <= 48.0 - 1.5]  # above the modifier, below the top skins
    assert len(inside) > 20 and len(outside) > 20
    assert inside == [5] * len(inside)
    assert outside == [2] * len(outside)
