"""The headless batch entry point: JSON report, PNG with legend, saved .blend, exit codes."""

import json
import os
import shutil
import subprocess

import bpy
import numpy as np
import pytest
from conftest import ROOT, blender_env
from osteon_blender import batch, bridge

BATCH = os.path.join(ROOT, "blender_addon", "osteon_blender", "batch.py")


def _png_pixels(path):
    img = bpy.data.images.load(path)
    try:
        w, h = img.size
        px = np.empty(w * h * 4, dtype=np.float32)
        img.pixels.foreach_get(px)
        return px.reshape(h, w, 4)
    finally:
        bpy.data.images.remove(img)


def test_batch_correct_writes_report_png_and_blend(sample, tmp_path):
    obj_name, arm_name = sample[0].name, sample[1].name
    rep, png, out = tmp_path / "r.json", tmp_path / "p.png", tmp_path / "o.blend"
    n_objects = len(bpy.data.objects)
    code = batch.run(["--report", str(rep), "--png", str(png), "--correct", "--save", str(out),
                      "--resolution", "400"])
    assert code == 0
    data = json.loads(rep.read_text())
    for key in ("max_stress_mpa", "allowable_stress_mpa", "weak_bones", "sections", "converged"):
        assert key in data
    assert data["allowable_stress_mpa"] == pytest.approx(30.0)
    assert data["converged"] is True and data["corrected"] is True
    assert data["max_stress_mpa"] <= 30.0 < data["correction"]["max_stress_before_mpa"]
    assert "tail" in data["correction"]["bone_scale"]
    tail = next(b for b in data["weak_bones"] if b["bone"] == "tail")
    assert tail["scale"] > 1.0 and tail["weak"] is False
    assert tail["max_stress_before_mpa"] > 30.0 >= tail["max_stress_mpa"]
    # PNG: the render has the stress colours (blue and red) and the legend
    px = _png_pixels(str(png))
    assert px.shape[1] == 400
    r, g, b = px[..., 0], px[..., 1], px[..., 2]
    red = (r > 0.5) & (g < 0.45 * r) & (b < 0.45 * r)  # top of the legend (lit by studio light)
    blue = (b > 0.5) & (r < 0.45 * b)
    assert red.sum() > 50 and blue.sum() > 50
    # the render helpers were cleaned up; the saved file has the layer and the pose scales
    assert len(bpy.data.objects) == n_objects
    assert out.is_file()
    bpy.ops.wm.open_mainfile(filepath=str(out))
    o = bpy.data.objects[obj_name]
    assert bridge.read_point_colors(o.data).shape == (len(o.data.vertices), 4)
    assert bpy.data.objects[arm_name].pose.bones["tail"].scale[0] > 1.0


def test_batch_settings_arguments(sample, tmp_path):
    rep = tmp_path / "r.json"
    assert batch.run(["--report", str(rep), "--material", "ABS", "--safety", "1.5",
                      "--force", "5", "--print-size", "200", "--interval", "3"]) == 0
    data = json.loads(rep.read_text())
    assert data["allowable_stress_mpa"] == pytest.approx(40.0 / 1.5)
    assert data["settings"]["force_n"] == 5.0 and data["settings"]["interval_mm"] == 3.0
    assert data["corrected"] is False


def _blender():
    return bpy.app.binary_path or shutil.which("blender")


@pytest.mark.skipif(not _blender(), reason="no Blender binary to run the batch command with")
def test_batch_command_exit_codes(tmp_path):
    exe = _blender()
    env = blender_env()
    bad = subprocess.run([exe, "-b", "--factory-startup", "--python", BATCH, "--",
                          "--report", str(tmp_path / "r.json")], check=False,
                         capture_output=True, text=True, env=env, timeout=300)
    assert bad.returncode != 0
    assert "no mesh with an Armature modifier" in bad.stderr
    assert not (tmp_path / "r.json").exists()
    blend = tmp_path / "s.blend"
    build = subprocess.run([exe, "-b", "--factory-startup", "--python",
                            os.path.join(ROOT, "blender_addon", "osteon_blender", "sample.py"), "--",
                            "--out", str(blend)],
                           check=False, capture_output=True, text=True, env=env, timeout=300)
    assert build.returncode == 0, build.stderr
    ok = subprocess.run([exe, "-b", str(blend), "--python", BATCH, "--",
                         "--report", str(tmp_path / "r.json")], check=False,
                        capture_output=True, text=True, env=env, timeout=300)
    assert ok.returncode == 0, ok.stdout + ok.stderr
    assert json.loads((tmp_path / "r.json").read_text())["sections"] > 50
