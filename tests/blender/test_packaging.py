"""The built packages install and run, each in the Blender it is for:

* the legacy zip (Blender 3.4-4.1, Python 3.10/3.11) with its vendored engine: installed with
  ``bpy.ops.preferences.addon_install`` in Debian's 3.4.1 and the bpy 4.5 wheel (Python 3.11);
* the 4.2+ extension zip with its bundled cp311 + cp313 wheels: Blender's own validator, then
  ``bpy.ops.extensions.package_install_files`` in the bpy 4.5 (cp311) and 5.2 (cp313) wheels.

Each install runs Analyze on the sample rig in a fresh Blender process that can only import
the engine the package brought, and must give the same result as the in-tree add-on here.
The zips come from scripts/build_addon.py (scripts/blender_tests.sh builds them first)."""

import glob
import inspect
import os
import re
import subprocess
import sys
import textwrap
import zipfile

import bpy
import pytest
from conftest import ROOT
from test_skeleton import _capsule

try:
    import tomllib
except ImportError:  # Python 3.10 (official Blender 3.4-4.0): manifest checks need 3.11
    tomllib = None

DIST = os.environ.get("OSTEON_DIST", os.path.join(ROOT, "dist"))
#: the bundled sample figurine's builder, loaded by path in the child Blenders
SAMPLE = os.path.join(ROOT, "blender_addon", "osteon_blender", "sample.py")
PY = "cp{}{}".format(*sys.version_info[:2])
LEGACY_PYTHONS = ("cp310", "cp311")  # official 3.4-4.0 / 4.1 and Debian's 3.4.1


def _zip(kind: str) -> str:
    found = sorted(glob.glob(os.path.join(DIST, f"osteon_blender-*-linux_x64-{kind}.zip")),
                   key=os.path.getmtime)
    if not found:
        pytest.fail(f"no linux_x64 {kind} zip in {DIST}: run scripts/build_addon.py first")
    return found[-1]


def _manifest(zip_path: str) -> dict:
    if tomllib is None:
        pytest.skip("tomllib needs Python 3.11")
    with zipfile.ZipFile(zip_path) as z:
        return tomllib.loads(z.read("blender_manifest.toml").decode("utf-8"))


def _run(script: str, env_extra: dict, tmp_path) -> str:
    path = tmp_path / "script.py"
    path.write_text(textwrap.dedent(script))
    env = dict(os.environ, **env_extra)
    if bpy.app.binary_path:  # a Blender binary
        cmd = [bpy.app.binary_path, "-b", "--factory-startup", "--python-exit-code", "1",
               "--python", str(path)]
    else:  # bpy as a Python module
        cmd = [sys.executable, str(path)]
    res = subprocess.run(cmd, check=False, capture_output=True, text=True, env=env, timeout=900)
    out = res.stdout + res.stderr
    assert res.returncode == 0, out
    return out


def _only_engine_under(root: str, names: tuple = ("osteon",)) -> str:
    """Child-process prelude: ``names`` ('osteon', and 'pygel3d' for Make skeleton) may only
    be imported from below ``root`` (the package's own copy), never from the environment's
    site-packages."""
    return f"""
import importlib.machinery, sys
class OnlyPackaged:
    def find_spec(self, name, path=None, target=None):
        if name not in {names!r}:
            return None
        spec = importlib.machinery.PathFinder.find_spec(
            name, [p for p in sys.path if p.startswith({root!r})])
        if spec is None:
            raise ModuleNotFoundError(name + ": not below {root} (hidden for the test)")
        return spec
sys.meta_path.insert(0, OnlyPackaged())
"""


_ANALYZE = """
import importlib.util
_spec = importlib.util.spec_from_file_location("osteon_sample", {sample!r})
make_sample_rig = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(make_sample_rig)
make_sample_rig.build()
result = bpy.ops.osteon.analyze()
import osteon
s = bpy.context.scene.osteon
print("ENGINE", osteon.__file__)
print("RESULT", result, s.sections, repr(s.max_stress_mpa))
"""


def _result(out: str) -> tuple[str, int, float]:
    m = re.search(r"^RESULT (\{.*?\}) (\d+) (\S+)$", out, re.MULTILINE)
    assert m, out
    return m.group(1), int(m.group(2)), float(m.group(3))


@pytest.fixture(scope="module")
def reference(addon):
    """Analyze of the sample rig by the in-tree add-on: (sections, max stress in MPa)."""
    from osteon_blender import sample as make_sample_rig

    bpy.ops.wm.read_factory_settings(use_empty=True)
    make_sample_rig.build()
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    s = bpy.context.scene.osteon
    return s.sections, s.max_stress_mpa


def _assert_same_result(out: str, reference):
    status, sections, max_stress = _result(out)
    assert status == "{'FINISHED'}", out
    assert sections > 0 and sections == reference[0]
    assert max_stress == pytest.approx(reference[1], rel=1e-6) and max_stress > 0


# --- the legacy zip (Blender 3.4-4.1) ---------------------------------------------------------

def test_legacy_zip_contents():
    with zipfile.ZipFile(_zip("legacy")) as z:
        names = z.namelist()
    assert "osteon_blender/__init__.py" in names
    assert not any(n.endswith("blender_manifest.toml") for n in names)  # else 4.2+ sees an extension
    cores = [n for n in names if re.match(r"osteon_blender/_vendor/osteon/_core\.", n)]
    assert any(".cpython-311-" in n for n in cores), cores  # 4.1 and Debian's 3.4.1
    if glob.glob(os.path.join(DIST, "osteon-*-cp310-*linux_x86_64.whl")):
        assert any(".cpython-310-" in n for n in cores), cores  # official 3.4-4.0


@pytest.mark.skipif(PY not in LEGACY_PYTHONS,
                    reason=f"the legacy zip is for Blender 3.4-4.1 (Python 3.10/3.11), not {PY}")
def test_legacy_zip_runs_with_vendored_engine(tmp_path, reference):
    zip_path = _zip("legacy")
    scripts = tmp_path / "scripts"
    script = _only_engine_under(str(scripts)) + f"""
import bpy
import addon_utils
bpy.ops.preferences.addon_install(filepath={zip_path!r})
addon_utils.enable("osteon_blender", default_set=True)
""" + _ANALYZE.format(sample=SAMPLE) + """
addon_utils.disable("osteon_blender")
"""
    out = _run(script, {"BLENDER_USER_SCRIPTS": str(scripts)}, tmp_path)
    engine = next(line for line in out.splitlines() if line.startswith("ENGINE"))
    assert "_vendor" in engine and str(scripts) in engine
    _assert_same_result(out, reference)


_SKELETON = """
import numpy as np
{capsule}
verts, faces = _capsule()
me = bpy.data.meshes.new("capsule")
me.from_pydata(verts, [], faces)
ob = bpy.data.objects.new("capsule", me)
bpy.context.scene.collection.objects.link(ob)
bpy.context.view_layer.objects.active = ob
ob.select_set(True)
res = bpy.ops.osteon.make_skeleton()
import pygel3d
arm = bpy.data.objects.get("capsule_skeleton")
print("PYGEL3D", pygel3d.__file__)
print("SKELETON", res, len(arm.data.bones) if arm else 0)
"""


def _assert_skeleton(out: str, root: str) -> None:
    gel = next(line for line in out.splitlines() if line.startswith("PYGEL3D"))
    assert root in gel, gel                       # the zip's own pygel3d, not the system's
    m = re.search(r"^SKELETON \{'FINISHED'\} (\d+)$", out, re.MULTILINE)
    assert m and int(m.group(1)) >= 1, out


@pytest.mark.skipif(PY not in LEGACY_PYTHONS,
                    reason=f"the legacy zip is for Blender 3.4-4.1 (Python 3.10/3.11), not {PY}")
def test_legacy_zip_makes_a_skeleton_with_its_own_pygel3d(tmp_path):
    """Make skeleton from the zip alone (issue 35): pygel3d comes from the zip's _vendor."""
    zip_path = _zip("legacy")
    with zipfile.ZipFile(zip_path) as z:
        if not any(n.startswith("osteon_blender/_vendor/pygel3d/") for n in z.namelist()):
            pytest.fail("the legacy zip carries no pygel3d (scripts/build_addon.py --pygel3d)")
    scripts = tmp_path / "scripts"
    script = _only_engine_under(str(scripts), ("osteon", "pygel3d")) + f"""
import bpy
import addon_utils
bpy.ops.preferences.addon_install(filepath={zip_path!r})
addon_utils.enable("osteon_blender", default_set=True)
""" + _SKELETON.format(capsule=inspect.getsource(_capsule))
    out = _run(script, {"BLENDER_USER_SCRIPTS": str(scripts)}, tmp_path)
    _assert_skeleton(out, str(scripts))


# --- the 4.2+ extension zip -------------------------------------------------------------------

def test_extension_manifest_says_what_the_zip_carries():
    import addon_build as build_addon

    zip_path = _zip("extension")
    m = _manifest(zip_path)
    with zipfile.ZipFile(zip_path) as z:
        names = set(z.namelist())
    assert "__init__.py" in names
    wheels = m["wheels"]
    assert wheels and all(w.startswith("./wheels/") for w in wheels)
    assert all(w[2:] in names for w in wheels), (wheels, sorted(names))
    assert sorted(n for n in names if n.endswith(".whl")) == sorted(w[2:] for w in wheels)
    tags = {w.rsplit("-", 3)[1] for w in wheels}
    assert {"cp311", "cp313"} <= tags, tags  # Blender 4.2-5.0 and 5.1+
    assert m["platforms"] == ["linux-x64"]
    assert {build_addon.platform_of(w) for w in wheels} == {"linux-x64"}
    assert m["blender_version_min"] == "4.2.0"
    assert "blender_version_max" not in m  # 5.1+ on 3.13; a later Python is refused by Blender
    assert len(m["tagline"]) <= 64
    assert m["version"] == build_addon.addon_version()


@pytest.mark.skipif(bpy.app.version < (4, 2, 0), reason="the validator exists from Blender 4.2")
def test_extension_zip_passes_blenders_validator(capfd):
    from bl_pkg import bl_extension_cli  # what `blender --command extension validate` runs

    zip_path = _zip("extension")
    capfd.readouterr()
    code = bl_extension_cli.cli_extension_handler(["validate", zip_path])
    out = "".join(capfd.readouterr())
    assert code == 0, out
    assert "Success parsing TOML" in out


@pytest.mark.skipif(bpy.app.version < (4, 2, 0), reason="the validator exists from Blender 4.2")
def test_validator_rejects_a_long_tagline(tmp_path, capfd):
    from bl_pkg import bl_extension_cli

    bad = tmp_path / "bad.zip"
    with zipfile.ZipFile(_zip("extension")) as z, zipfile.ZipFile(bad, "w") as out:
        for info in z.infolist():
            data = z.read(info)
            if info.filename == "blender_manifest.toml":
                data = re.sub(rb'(?m)^tagline = ".*"$', b'tagline = "' + b"x" * 65 + b'"', data)
            out.writestr(info, data)
    capfd.readouterr()
    assert bl_extension_cli.cli_extension_handler(["validate", str(bad)]) != 0
    assert "no longer than 64" in "".join(capfd.readouterr())


@pytest.mark.skipif(bpy.app.version < (4, 2, 0), reason="extensions exist from Blender 4.2")
def test_extension_zip_installs_its_wheel_and_analyzes(tmp_path, reference):
    zip_path = _zip("extension")
    res = tmp_path / "resources"
    script = _only_engine_under(str(res)) + f"""
import bpy
r = bpy.ops.extensions.package_install_files(filepath={zip_path!r}, repo="user_default",
                                             enable_on_install=True)
print("INSTALL", r)
print("MODULE", bpy.types.OSTEON_OT_analyze.__module__)
""" + _ANALYZE.format(sample=SAMPLE)
    out = _run(script, {"BLENDER_USER_RESOURCES": str(res)}, tmp_path)
    assert "INSTALL {'FINISHED'}" in out, out
    assert "MODULE bl_ext.user_default.osteon_blender" in out
    engine = next(line for line in out.splitlines() if line.startswith("ENGINE"))
    assert str(res) in engine and "site-packages" in engine, engine
    # Blender installed the wheel of its own Python, and only that one
    infos = [d for _, dirs, _ in os.walk(res) for d in dirs
             if d.startswith("osteon-") and d.endswith(".dist-info")]
    assert len(infos) == 1, infos
    cores = [f for _, _, files in os.walk(res) for f in files if f.startswith("_core.")]
    assert cores and all(f".cpython-{PY[2:]}-" in f for f in cores), cores
    _assert_same_result(out, reference)


@pytest.mark.skipif(bpy.app.version < (4, 2, 0), reason="extensions exist from Blender 4.2")
def test_extension_zip_makes_a_skeleton_with_its_own_pygel3d(tmp_path):
    """Make skeleton from the extension alone (issue 35): Blender installs the zip's pygel3d
    wheel beside the engine's."""
    zip_path = _zip("extension")
    res = tmp_path / "resources"
    script = _only_engine_under(str(res), ("osteon", "pygel3d")) + f"""
import bpy
r = bpy.ops.extensions.package_install_files(filepath={zip_path!r}, repo="user_default",
                                             enable_on_install=True)
print("INSTALL", r)
""" + _SKELETON.format(capsule=inspect.getsource(_capsule))
    out = _run(script, {"BLENDER_USER_RESOURCES": str(res)}, tmp_path)
    assert "INSTALL {'FINISHED'}" in out, out
    _assert_skeleton(out, str(res))
