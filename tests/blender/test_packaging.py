"""The built packages install and run: the legacy zip with its vendored engine (any
Blender), the 4.2+ extension zip with its bundled wheel (bpy 4.5).  The zips come from
scripts/build_addon.py (scripts/blender_tests.sh builds them first)."""

import glob
import os
import subprocess
import sys
import textwrap

import bpy
import pytest
from conftest import ROOT

DIST = os.environ.get("OSTEON_DIST", os.path.join(ROOT, "dist"))


def _zip(kind: str) -> str:
    found = sorted(glob.glob(os.path.join(DIST, f"osteon_blender-*-{kind}.zip")))
    if not found:
        pytest.fail(f"no {kind} zip in {DIST}: run scripts/build_addon.py first")
    return found[-1]


def _run(script: str, env_extra: dict, tmp_path) -> str:
    path = tmp_path / "script.py"
    path.write_text(textwrap.dedent(script))
    env = dict(os.environ, **env_extra)
    if bpy.app.binary_path:  # a Blender binary
        cmd = [bpy.app.binary_path, "-b", "--factory-startup", "--python-exit-code", "1",
               "--python", str(path)]
    else:  # bpy as a Python module
        cmd = [sys.executable, str(path)]
    res = subprocess.run(cmd, check=False, capture_output=True, text=True, env=env, timeout=600)
    out = res.stdout + res.stderr
    assert res.returncode == 0, out
    return out


_HIDE_INSTALLED_ENGINE = """
import importlib.machinery, sys
class OnlyVendored:
    # 'osteon' may only come from an add-on's _vendor folder
    def find_spec(self, name, path=None, target=None):
        if name != "osteon":
            return None
        spec = importlib.machinery.PathFinder.find_spec(
            name, [p for p in sys.path if p.endswith("_vendor")])
        if spec is None:
            raise ModuleNotFoundError("osteon (hidden for the test)")
        return spec
sys.meta_path.insert(0, OnlyVendored())
"""


def test_legacy_zip_runs_with_vendored_engine(tmp_path):
    zip_path = _zip("legacy")
    script = _HIDE_INSTALLED_ENGINE + f"""
import bpy
import addon_utils
sys.path.insert(0, {os.path.join(ROOT, "scripts")!r})
bpy.ops.preferences.addon_install(filepath={zip_path!r})
addon_utils.enable("osteon_blender", default_set=True)
import make_sample_rig
make_sample_rig.build()
result = bpy.ops.osteon.analyze()
import osteon
print("ENGINE", osteon.__file__)
n = len(bpy.context.active_object.data.attributes["osteon_stress"].data)
print("RESULT", result, n)
addon_utils.disable("osteon_blender")
"""
    out = _run(script, {"BLENDER_USER_SCRIPTS": str(tmp_path / "scripts")}, tmp_path)
    assert "RESULT {'FINISHED'}" in out
    engine_line = next(line for line in out.splitlines() if line.startswith("ENGINE"))
    assert "_vendor" in engine_line and str(tmp_path) in engine_line


@pytest.mark.skipif(bpy.app.version < (4, 2, 0), reason="extensions exist from Blender 4.2")
def test_extension_zip_installs_bundled_wheel(tmp_path):
    zip_path = _zip("extension")
    res = tmp_path / "resources"
    script = f"""
import bpy, os, sys
sys.path.insert(0, {os.path.join(ROOT, "scripts")!r})
r = bpy.ops.extensions.package_install_files(filepath={zip_path!r}, repo="user_default",
                                             enable_on_install=True)
import make_sample_rig
make_sample_rig.build()
print("RESULT", r, bpy.ops.osteon.analyze())
print("MODULE", bpy.types.OSTEON_OT_analyze.__module__)
"""
    out = _run(script, {"BLENDER_USER_RESOURCES": str(res)}, tmp_path)
    assert "RESULT {'FINISHED'} {'FINISHED'}" in out
    assert "MODULE bl_ext.user_default.osteon_blender" in out
    cores = [os.path.join(d, f) for d, _, files in os.walk(res) for f in files
             if f.startswith("_core") and f.endswith(".so") and "osteon" in d]
    assert cores, "the bundled osteon wheel was not installed"
