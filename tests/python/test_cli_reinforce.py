"""``osteon reinforce`` end to end on a rod written here (OBJ + TGF): exit codes, the JSON
report's reinforcement block, the slicer project it writes, one-line errors."""

from __future__ import annotations

import io
import json
import xml.etree.ElementTree as ET
import zipfile

import pytest
from osteon.cli import main
from osteon.settings import engine_takes_print_profile
from shapes import cylinder_along

pytestmark = pytest.mark.skipif(not engine_takes_print_profile(),
                                reason="this engine has no printed section (print_profile=)")


@pytest.fixture
def rod(tmp_path):
    """A standing rod r = 8 mm, 48 mm tall (z -4 .. 44), one bone z 0 .. 40."""
    v, f = cylinder_along((0, 0, -4), (0, 0, 44), 8.0, n=64, stations=24)
    path = tmp_path / "rod.obj"
    lines = [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in v]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in f]
    path.write_text("\n".join(lines) + "\n")
    (tmp_path / "rod.tgf").write_text("1 0 0 0\n2 0 0 40\n#\n1 2\n#\n")
    return path


ARGS = ["--height-mm", "48", "--axis", "z", "--force", "40", "--safety-factor", "1",
        "--profile", "prusaslicer", "--perimeters", "2", "--infill", "15", "-q"]


def test_reinforce_writes_the_project_and_the_report(rod, tmp_path, capsys):
    out, js = tmp_path / "rod.3mf", tmp_path / "r.json"
    rc = main(["reinforce", str(rod), *ARGS, "--strength-mpa", "10", "--out", str(out),
               "--json", str(js)])
    assert rc == 0, capsys.readouterr().err
    rep = json.loads(js.read_text())
    block = rep["reinforcement"]
    assert block["slicer"] == "prusaslicer" and block["slicer_project"] == str(out)
    assert block["print_profile"]["perimeters"] == 2
    (row,) = block["regions"]
    assert row["perimeters_before"] == 2 and row["perimeters"] > 2
    assert row["stress_before_mpa"] > 10.0 >= row["stress_after_mpa"]
    assert row["extra_volume_mm3"] > 0 and row["fixed"] and not block["unfixable"]
    with zipfile.ZipFile(out) as z:
        cfg = ET.fromstring(z.read("Metadata/Slic3r_PE_model.config"))
    vols = cfg.find("object").findall("volume")
    mods = [{m.get("key"): m.get("value") for m in v.findall("metadata")} for v in vols[1:]]
    assert [int(m["perimeters"]) for m in mods] == [row["perimeters"]]
    assert [m["fill_density"] for m in mods] == [f"{100 * row['infill']:.4g}%"]


def test_reinforce_errors_are_one_line(rod, tmp_path, capsys):
    rc = main(["reinforce", str(rod), *ARGS, "--out", str(tmp_path / "x.stl")])
    err = capsys.readouterr().err
    assert rc == 2 and ".3mf" in err and err.count("\n") == 1
    args = [a if a != "prusaslicer" else "solid" for a in ARGS]
    args = [a for a in args if a not in ("--perimeters", "2", "--infill", "15")]
    rc = main(["reinforce", str(rod), *args, "--out", str(tmp_path / "x.3mf")])
    err = capsys.readouterr().err
    assert rc == 2 and "FDM" in err and err.count("\n") == 1
    assert not (tmp_path / "x.3mf").exists()


def test_batch_writes_a_slicer_project_per_model(rod):
    from osteon.batch.task import process_model

    rec = process_model(str(rod), {
        "force_n": 40.0, "material": "CUSTOM", "strength_mpa": 10.0, "safety_factor": 1.0,
        "size_mode": "HEIGHT", "print_size_mm": 48.0, "print_profile": "prusaslicer",
        "perimeters": 2, "infill": 0.15, "png": False, "slicer_project": "bambu"})
    assert rec["status"] == "ok", rec["reason"]
    block = rec["reinforcement"]
    assert block["slicer"] == "bambu" and block["slicer_project"] == "rod.3mf"
    (row,) = block["regions"]
    with zipfile.ZipFile(io.BytesIO(rec["_files"]["rod.3mf"])) as z:
        cfg = ET.fromstring(z.read("Metadata/model_settings.config"))
    parts = cfg.find("object").findall("part")
    mods = [{m.get("key"): m.get("value") for m in p.findall("metadata")} for p in parts
            if p.get("subtype") == "modifier_part"]
    assert [int(m["wall_loops"]) for m in mods] == [row["perimeters"]]
