"""The wheel builds for other platforms, as far as they can be checked here: the
[tool.cibuildwheel] configuration in pyproject.toml, cibuildwheel's reading of it (when
cibuildwheel is installed), and .github/workflows/wheels.yml."""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import sys

import pytest

tomllib = pytest.importorskip("tomllib")
yaml = pytest.importorskip("yaml")

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
WORKFLOW = os.path.join(ROOT, ".github", "workflows", "wheels.yml")

PYTHONS = ("cp310", "cp311", "cp313")  # legacy 3.4-4.0; 4.1-5.0; 5.1+
IDENTIFIERS = {
    "linux": {f"{py}-manylinux_{a}" for py in PYTHONS for a in ("x86_64", "aarch64")},
    "windows": {f"{py}-win_amd64" for py in PYTHONS},
    "macos": {f"{py}-macosx_{a}" for py in PYTHONS for a in ("x86_64", "arm64")},
}


@pytest.fixture(scope="module")
def cibw() -> dict:
    with open(os.path.join(ROOT, "pyproject.toml"), "rb") as fh:
        return tomllib.load(fh)["tool"]["cibuildwheel"]


def test_cibuildwheel_config(cibw):
    assert cibw["build"] == [f"{py}-*" for py in PYTHONS]
    lin = cibw["linux"]
    assert set(lin["archs"]) == {"x86_64", "aarch64"}
    assert lin["manylinux-x86_64-image"] == lin["manylinux-aarch64-image"] == "manylinux_2_28"
    assert "eigen3-devel" in lin["before-all"]
    assert "eigen" in cibw["macos"]["before-all"] and "eigen3" in cibw["windows"]["before-all"]
    assert set(cibw["macos"]["archs"]) == {"x86_64", "arm64"}
    assert cibw["windows"]["archs"] == ["AMD64"]
    # the smoke test it runs exists and names the project root the cibuildwheel way
    cmd = cibw["test-command"]
    script = cmd.split("{project}/", 1)[1].split()[0]
    assert os.path.isfile(os.path.join(ROOT, script)), cmd


@pytest.mark.parametrize("platform", sorted(IDENTIFIERS))
def test_cibuildwheel_build_identifiers(platform, tmp_path):
    if os.environ.get("OSTEON_CIBUILDWHEEL"):
        cmd = [os.environ["OSTEON_CIBUILDWHEEL"]]
    elif importlib.util.find_spec("cibuildwheel"):  # a test dependency (pyproject [test])
        cmd = [sys.executable, "-m", "cibuildwheel"]
    elif shutil.which("cibuildwheel"):
        cmd = [shutil.which("cibuildwheel")]
    else:
        pytest.skip("cibuildwheel not installed (pip install cibuildwheel; or OSTEON_CIBUILDWHEEL)")
    env = {k: v for k, v in os.environ.items() if not k.startswith("CIBW_")}
    res = subprocess.run([*cmd, "--print-build-identifiers", "--platform", platform, ROOT],
                         capture_output=True, text=True, cwd=tmp_path, env=env, timeout=120,
                         check=False)
    assert res.returncode == 0, res.stderr
    assert set(res.stdout.split()) == IDENTIFIERS[platform]


@pytest.fixture(scope="module")
def workflow() -> dict:
    with open(WORKFLOW, encoding="utf-8") as fh:
        return yaml.safe_load(fh)


def _steps_text(job: dict) -> str:
    return "\n".join(str(s.get("run", "")) + str(s.get("uses", "")) for s in job["steps"])


def test_workflow_triggers(workflow):
    on = workflow.get("on", workflow.get(True))  # YAML 1.1 reads a bare `on` as True
    assert {"push", "pull_request", "workflow_dispatch"} <= set(on)


def test_workflow_builds_every_platform(workflow):
    job = workflow["jobs"]["wheels"]
    matrix = job["strategy"]["matrix"]["include"]
    assert job["runs-on"] == "${{ matrix.os }}"
    archs = {a for row in matrix for a in row["archs"].split()}
    assert archs == {"x86_64", "aarch64", "AMD64", "arm64"}
    oses = {row["os"].split("-")[0] for row in matrix}
    assert oses == {"ubuntu", "windows", "macos"}
    assert any(row["os"].endswith("-arm") and row["archs"] == "aarch64" for row in matrix)
    steps = _steps_text(job)
    assert "actions/checkout" in steps and "python -m cibuildwheel --output-dir wheelhouse" in steps
    build = next(s for s in job["steps"] if "cibuildwheel --output-dir" in str(s.get("run")))
    assert build["env"]["CIBW_ARCHS"] == "${{ matrix.archs }}"
    upload = next(s for s in job["steps"] if str(s.get("uses", "")).startswith(
        "actions/upload-artifact"))
    assert upload["with"]["path"] == "wheelhouse/*.whl"


def test_workflow_assembles_the_blender_zips(workflow):
    job = workflow["jobs"]["addon"]
    assert job["needs"] == "wheels"
    steps = _steps_text(job)
    assert "actions/download-artifact" in steps
    assert "scripts/build_addon.py --wheel-dir wheelhouse" in steps
    assert "--validate-with" in steps and "bpy==5.2" in steps
    upload = next(s for s in job["steps"] if str(s.get("uses", "")).startswith(
        "actions/upload-artifact"))
    assert "dist/*.zip" in upload["with"]["path"]
    py = next(s for s in job["steps"] if str(s.get("uses", "")).startswith("actions/setup-python"))
    assert py["with"]["python-version"] == "3.13"  # the bpy 5.2 wheel is cp313
