"""scripts/build_addon.py without Blender: which Blender releases a set of wheels covers, the
platform of each wheel tag, and the zips it writes for made-up wheels of two platforms."""

from __future__ import annotations

import os
import sys
import zipfile

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import build_addon

tomllib = pytest.importorskip("tomllib")


@pytest.mark.parametrize("pythons, expected", [
    ({(3, 11), (3, 13)}, ("4.2.0", None)),  # 4.2-5.0 and 5.1+
    ({(3, 11)}, ("4.2.0", "5.1.0")),  # 5.1 embeds 3.13: excluded (max is exclusive)
    ({(3, 13)}, ("5.1.0", None)),
    ({(3, 10), (3, 11), (3, 13)}, ("4.2.0", None)),  # cp310 is for the legacy zip only
])
def test_blender_range(pythons, expected):
    assert build_addon.blender_range(pythons) == expected


def test_blender_range_needs_a_42_python():
    with pytest.raises(SystemExit, match="cp311, cp313"):
        build_addon.blender_range({(3, 10)})


def test_blender_python_table():
    t = build_addon.BLENDER_PYTHON
    assert t[(4, 0)] == (3, 10) and t[(4, 1)] == (3, 11) and t[(5, 0)] == (3, 11)
    assert t[(5, 1)] == (3, 13) and t[(5, 2)] == (3, 13)
    assert build_addon.EXTENSION_PYTHONS == {(3, 11), (3, 13)}


@pytest.mark.parametrize("tag, platform", [
    ("linux_x86_64", "linux-x64"),
    ("manylinux_2_27_x86_64.manylinux_2_28_x86_64", "linux-x64"),
    ("manylinux_2_28_aarch64", "linux-arm64"),
    ("win_amd64", "windows-x64"),
    ("macosx_11_0_arm64", "macos-arm64"),
    ("macosx_10_15_x86_64", "macos-x64"),
])
def test_platform_of(tag, platform):
    assert build_addon.platform_of(f"osteon-0.1.0-cp313-cp313-{tag}.whl") == platform


def _fake_wheel(folder, py: str, tag: str, suffix: str) -> str:
    path = os.path.join(folder, f"osteon-0.1.0-{py}-{py}-{tag}.whl")
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("osteon/__init__.py", "__version__ = '0.1.0'\n")
        z.writestr(f"osteon/_core{suffix}", b"\0")
        z.writestr("osteon-0.1.0.dist-info/WHEEL", "Wheel-Version: 1.0\n")
    return path


def test_zips_per_platform(tmp_path):
    wh = tmp_path / "wheelhouse"
    wh.mkdir()
    lin = "manylinux_2_27_x86_64.manylinux_2_28_x86_64"
    for py in ("cp310", "cp311", "cp313"):
        _fake_wheel(wh, py, lin, f".cpython-{py[2:]}-x86_64-linux-gnu.so")
    for py in ("cp311", "cp313"):
        _fake_wheel(wh, py, "win_amd64", f".{py}-win_amd64.pyd")
    out = tmp_path / "dist"
    assert build_addon.main(["--wheel-dir", str(wh), "--out", str(out)]) == 0
    v = build_addon.addon_version()
    zips = sorted(p.name for p in out.glob("*.zip"))
    assert zips == [f"osteon_blender-{v}-linux_x64-extension.zip",
                    f"osteon_blender-{v}-linux_x64-legacy.zip",
                    f"osteon_blender-{v}-windows_x64-extension.zip",
                    f"osteon_blender-{v}-windows_x64-legacy.zip"]

    with zipfile.ZipFile(out / f"osteon_blender-{v}-windows_x64-extension.zip") as z:
        m = tomllib.loads(z.read("blender_manifest.toml").decode())
        names = set(z.namelist())
    assert m["platforms"] == ["windows-x64"]
    assert m["wheels"] == [f"./wheels/osteon-0.1.0-{py}-{py}-win_amd64.whl"
                           for py in ("cp311", "cp313")]
    assert {w[2:] for w in m["wheels"]} <= names and "__init__.py" in names
    assert m["blender_version_min"] == "4.2.0" and "blender_version_max" not in m
    assert len(m["tagline"]) <= 64 and m["version"] == v

    with zipfile.ZipFile(out / f"osteon_blender-{v}-linux_x64-extension.zip") as z:
        m = tomllib.loads(z.read("blender_manifest.toml").decode())
    assert [w.split("-")[2] for w in m["wheels"]] == ["cp311", "cp313"]  # no cp310 in 4.2+
    assert m["platforms"] == ["linux-x64"]

    with zipfile.ZipFile(out / f"osteon_blender-{v}-linux_x64-legacy.zip") as z:
        names = z.namelist()
    assert "osteon_blender/__init__.py" in names
    assert not any(n.endswith("blender_manifest.toml") for n in names)
    cores = sorted(n for n in names if "/_vendor/osteon/_core" in n)
    assert cores == [f"osteon_blender/_vendor/osteon/_core.cpython-{p}-x86_64-linux-gnu.so"
                     for p in ("310", "311")]  # side by side; no 3.13 in Blender <= 4.1
    assert "osteon_blender/_vendor/osteon/__init__.py" in names
    assert not any("dist-info" in n for n in names)


def test_cp311_only_zip_stops_before_51(tmp_path):
    wh = tmp_path / "wh"
    wh.mkdir()
    _fake_wheel(wh, "cp311", "linux_x86_64", ".cpython-311-x86_64-linux-gnu.so")
    build_addon.main(["--wheel-dir", str(wh), "--out", str(tmp_path)])
    (ext,) = tmp_path.glob("*-extension.zip")
    with zipfile.ZipFile(ext) as z:
        m = tomllib.loads(z.read("blender_manifest.toml").decode())
    assert (m["blender_version_min"], m["blender_version_max"]) == ("4.2.0", "5.1.0")


def test_source_manifest_is_what_blender_accepts():
    with open(os.path.join(build_addon.ADDON, "blender_manifest.toml"), "rb") as fh:
        m = tomllib.load(fh)
    assert len(m["tagline"]) <= 64 and m["tagline"][-1].isalnum()
    assert m["version"] == build_addon.addon_version()
