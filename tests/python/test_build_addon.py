"""scripts/build_addon.py without Blender: which Blender releases a set of wheels covers, the
platform of each wheel tag, and the zips it writes for made-up wheels of two platforms."""

from __future__ import annotations

import os
import sys
import zipfile

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "blender_addon"))
import addon_build as build_addon

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
    gel = tmp_path / "gel"    # pygel3d for Linux x64 only (PyPI has none for some platforms)
    gel.mkdir()
    gel_wheel = "pygel3d-0.8.2-py3-none-manylinux_2_27_x86_64.manylinux_2_28_x86_64.whl"
    with zipfile.ZipFile(gel / gel_wheel, "w") as z:
        z.writestr("pygel3d/__init__.py", "")
        z.writestr("pygel3d/libPyGEL.so", b"\0")
        z.writestr("pygel3d.libs/libGLU-ff1477cc.so.1.3.1", b"\0")
        z.writestr("pygel3d-0.8.2.dist-info/WHEEL", "Wheel-Version: 1.0\n")
    out = tmp_path / "dist"
    assert build_addon.main(["--wheel-dir", str(wh), "--out", str(out),
                             "--pygel3d", str(gel)]) == 0
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
    assert "docs/blender.md" in names          # the Preferences' Documentation button
    assert m["blender_version_min"] == "4.2.0" and "blender_version_max" not in m
    assert len(m["tagline"]) <= 64 and m["version"] == v

    with zipfile.ZipFile(out / f"osteon_blender-{v}-linux_x64-extension.zip") as z:
        m = tomllib.loads(z.read("blender_manifest.toml").decode())
    # no cp310 in 4.2+; pygel3d's wheel listed after the engine's, so Blender installs it
    assert [w.split("-")[2] for w in m["wheels"]] == ["cp311", "cp313", "py3"]
    assert m["wheels"][-1] == f"./wheels/{gel_wheel}"
    assert m["platforms"] == ["linux-x64"]

    with zipfile.ZipFile(out / f"osteon_blender-{v}-linux_x64-legacy.zip") as z:
        names = z.namelist()
    assert "osteon_blender/__init__.py" in names
    assert not any(n.endswith("blender_manifest.toml") for n in names)
    cores = sorted(n for n in names if "/_vendor/osteon/_core" in n)
    assert cores == [f"osteon_blender/_vendor/osteon/_core.cpython-{p}-x86_64-linux-gnu.so"
                     for p in ("310", "311")]  # side by side; no 3.13 in Blender <= 4.1
    assert "osteon_blender/_vendor/osteon/__init__.py" in names
    assert {"osteon_blender/_vendor/pygel3d/libPyGEL.so", "osteon_blender/docs/blender.md",
            "osteon_blender/_vendor/pygel3d.libs/libGLU-ff1477cc.so.1.3.1"} <= set(names)
    assert not any("dist-info" in n for n in names)
    with zipfile.ZipFile(out / f"osteon_blender-{v}-windows_x64-legacy.zip") as z:
        assert not any("pygel3d" in n for n in z.namelist())   # none given for Windows


@pytest.mark.parametrize("wheel, platforms", [
    ("pygel3d-0.8.2-py3-none-manylinux_2_27_x86_64.manylinux_2_28_x86_64.whl", ["linux-x64"]),
    ("pygel3d-0.8.2-py3-none-manylinux_2_27_aarch64.manylinux_2_28_aarch64.whl",
     ["linux-arm64"]),
    ("pygel3d-0.8.2-py3-none-win_amd64.whl", ["windows-x64"]),
    ("pygel3d-0.8.2-py3-none-macosx_11_0_universal2.whl", ["macos-arm64", "macos-x64"]),
])
def test_pygel3d_wheel_platforms(wheel, platforms):
    """The four wheels PyPI has for PyGEL3D 0.8.2 (pip download --platform ..., 2026-11-27)."""
    assert build_addon.pygel3d_platform(wheel) == platforms


def test_cp311_only_zip_stops_before_51(tmp_path):
    wh = tmp_path / "wh"
    wh.mkdir()
    _fake_wheel(wh, "cp311", "linux_x86_64", ".cpython-311-x86_64-linux-gnu.so")
    build_addon.main(["--wheel-dir", str(wh), "--out", str(tmp_path), "--pygel3d", "none"])
    (ext,) = tmp_path.glob("*-extension.zip")
    with zipfile.ZipFile(ext) as z:
        m = tomllib.loads(z.read("blender_manifest.toml").decode())
    assert (m["blender_version_min"], m["blender_version_max"]) == ("4.2.0", "5.1.0")


def test_source_manifest_is_what_blender_accepts():
    with open(os.path.join(build_addon.ADDON, "blender_manifest.toml"), "rb") as fh:
        m = tomllib.load(fh)
    assert len(m["tagline"]) <= 64 and m["tagline"][-1].isalnum()
    assert m["version"] == build_addon.addon_version()
