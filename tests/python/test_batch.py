"""osteon batch: statuses of good and bad files, numbers equal to a direct analysis, outputs,
--resume after a kill, and the Dask path against the process pool."""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import osteon
import pytest
from batch_library import make_library, rigged_bar
from osteon import batch, materials
from osteon.cli import main as cli_main
from osteon.io import load_model

SETTINGS = {"force_n": 20.0, "material": "PLA", "print_size_mm": 120.0, "interval_mm": 2.0,
            "safety_factor": 1.0}
PLA_MPA = materials.get("PLA").strength_mpa


@pytest.fixture()
def library(tmp_path):
    lib = tmp_path / "lib"
    return lib, make_library(lib)


def _by_name(records):
    return {Path(r["model"]).name: r for r in records}


def test_discover_folders_globs_and_files(library, tmp_path):
    lib, expected = library
    found = batch.discover([lib])
    assert sorted(Path(m.path).name for m in found) == sorted(expected)
    assert len({m.id for m in found}) == len(found)
    # a glob picks model files only; a file named twice is listed once
    g = batch.discover([str(lib / "**" / "*.obj"), lib / "thin.obj"])
    assert sorted(Path(m.path).name for m in g) == ["empty.obj", "open.obj", "thick.obj", "thin.obj"]
    with pytest.raises(ValueError, match="input not found"):
        batch.discover([tmp_path / "nope"])
    with pytest.raises(ValueError, match="no file matches"):
        batch.discover([str(tmp_path / "*.nothing")])


def test_statuses_and_reasons(library):
    lib, expected = library
    recs = _by_name(batch.run_all([lib], SETTINGS, workers=1))
    assert {k: r["status"] for k, r in recs.items()} == expected
    if not hasattr(osteon, "auto_skeleton"):
        assert recs["unrigged.stl"]["reason"] == "no skeleton (auto_skeleton not available)"
    assert recs["open.obj"]["reason"].startswith("open mesh: ")
    assert recs["garbage.stl"]["reason"].startswith("unreadable:")
    assert recs["empty.obj"]["reason"].startswith("unreadable:")
    for r in recs.values():
        assert r["seconds"] >= 0 and "_files" not in r


def test_unrigged_mesh_uses_auto_skeleton_when_there_is_one(library, monkeypatch):
    """When osteon.auto_skeleton exists (issue 17), an unrigged mesh is rigged with it."""
    lib, _ = library
    calls = []

    def fake_auto_skeleton(vertices, faces, min_thickness=None):
        calls.append(min_thickness)
        x0, x1 = vertices[:, 0].min(), vertices[:, 0].max()
        mid = 0.5 * (x0 + x1)
        sk = osteon.Skeleton([[x0, 0, 0], [mid, 0, 0]], [[mid, 0, 0], [x1, 0, 0]], [-1, 0])
        return sk, None

    monkeypatch.setattr(osteon, "auto_skeleton", fake_auto_skeleton, raising=False)
    # in this process (no time limit: -j 1 with a limit runs in a worker process)
    (r,) = batch.run_all([lib / "unrigged.stl"], {**SETTINGS, "model_timeout_s": 0}, workers=1)
    assert r["status"] == "ok", r["reason"]
    assert "auto skeleton" in r["flags"]
    assert calls and r["bone_count"] == 2
    # limbs thinner than the material prints get no bone: the preset's minimum is passed on
    assert calls[0] == materials.get("PLA").min_thickness_mm
    # the bar is scaled to 120 mm before the skeleton is made (mm in, mm out)
    assert r["faces"] > 0 and r["max_stress_mpa"] > 0


def test_open_mesh_allowed_is_flagged(library):
    lib, _ = library
    (r,) = batch.run_all([lib / "open.obj"], {**SETTINGS, "allow_open": True}, workers=1)
    assert r["status"] == "ok"
    assert any(f.startswith("open mesh:") for f in r["flags"])


def test_numbers_equal_direct_analysis(library):
    lib, _ = library
    recs = _by_name(batch.run_all([lib], SETTINGS, workers=2))
    for name in ("thin.obj", "thick.obj", "sub/deeper/short.ply"):
        path = lib / name
        m = load_model(path, height_mm=120.0)
        a = osteon.analyze(m.vertices, m.faces, m.skeleton, m.weights, force=20.0,
                           allowable_stress=PLA_MPA, interval=2.0)
        r = recs[path.name]
        assert r["max_stress_mpa"] == pytest.approx(a.max_stress, rel=1e-12)
        assert r["stress_ratio"] == pytest.approx(a.max_stress / PLA_MPA, rel=1e-12)
        assert r["schema_version"] == 2 and r["run"]["front_end"] == "batch"
        assert r["faces"] == len(m.faces) and r["bone_count"] == 2
        assert r["sections"] == len(a.stress)
    # a thinner bar of the same length is more stressed (W ~ r^3)
    assert recs["thin.obj"]["max_stress_mpa"] > recs["thick.obj"]["max_stress_mpa"]


def test_outputs(library, tmp_path):
    lib, expected = library
    out = tmp_path / "out"
    recs = batch.run_all([lib], SETTINGS, workers=1, out=out)
    lines = (out / "results.jsonl").read_text().splitlines()
    assert len(lines) == len(expected)
    ok = [r for r in recs if r["status"] == "ok"]
    for r in ok:
        rep = json.loads((out / r["json"]).read_text())
        assert rep["max_stress_mpa"] == r["max_stress_mpa"]
        assert len(rep["section_table"]) == rep["sections"] > 0
        png = (out / "models" / r["png"]).read_bytes()
        assert png[:8] == b"\x89PNG\r\n\x1a\n"
    with open(out / "summary.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert [c for c in rows[0]] == ["model", "faces", "bones", "max_stress_mpa", "ratio",
                                    "weak_bones", "flags", "status", "seconds"]
    ratios = [float(r["ratio"]) for r in rows if r["ratio"]]
    assert ratios == sorted(ratios, reverse=True) and len(ratios) == len(ok)
    assert [r["status"].split(":")[0] for r in rows[len(ok):]] and all(
        not r["ratio"] for r in rows[len(ok):])
    html = (out / "summary.html").read_text()
    assert html.count("<tr data-ratio=") == len(expected)
    assert "addEventListener('click'" in html
    # weakest first: the thin bar is listed before the thick one
    assert html.index("thin.obj") < html.index("thick.obj")


def test_correction_writes_meshes(tmp_path):
    lib = tmp_path / "lib"
    lib.mkdir()
    rigged_bar(lib, "thin", radius=2.5)
    out = tmp_path / "out"
    (r,) = batch.run_all([lib], {**SETTINGS, "correct": True, "force_n": 60.0}, workers=1, out=out)
    assert r["status"] == "ok" and r["max_stress_before_mpa"] > r["allowable_stress_mpa"]
    assert r["converged"] and r["stress_ratio"] <= 1.0 and r["corrected"]
    corrected = out / "models" / r["output"]
    assert corrected.stat().st_size > 0


def test_a_crashing_worker_fails_only_its_model(tmp_path):
    from batch_library import crashing_task
    from osteon.batch.runner import _pool

    lib = tmp_path / "lib"
    lib.mkdir()
    for i in range(3):
        rigged_bar(lib, f"bar{i}", radius=3.0 + i)
    rigged_bar(lib, "crash", radius=4.0)
    s = batch.BatchSettings.from_any({**SETTINGS, "png": False})
    recs = _by_name(_pool(batch.discover([lib]), s, 2, task=crashing_task))
    assert len(recs) == 4
    assert recs["crash.obj"]["status"] == "failed"
    assert "crashed" in recs["crash.obj"]["reason"]
    assert all(r["status"] == "ok" for k, r in recs.items() if k != "crash.obj")


def test_workers_live_on_and_only_a_failed_model_costs_a_new_one(tmp_path):
    """2 workers, 12 models: each worker takes model after model (2 processes for the good
    ones, not one per model); a model that exits its worker, one that segfaults and one over
    the time limit each fail with their reason and cost one fresh worker; every other model
    is ok."""
    from batch_library import pid_task
    from osteon.batch.runner import _pool

    names = [f"m{i}" for i in range(9)] + ["crash", "segv", "hang"]
    for n in names:
        (tmp_path / f"{n}.stl").write_bytes(b"")
    s = batch.BatchSettings.from_any({**SETTINGS, "model_timeout_s": 2.0})
    recs = _by_name(_pool(batch.discover([tmp_path]), s, 2, task=pid_task, timeout=2.0))
    assert len(recs) == 12
    assert "crashed" in recs["crash.stl"]["reason"] and "exit code 3" in recs["crash.stl"]["reason"]
    # SIGSEGV: exit code -11 (-6 under AddressSanitizer, whose SEGV handler aborts:
    # scripts/sanitize.sh runs this suite with the sanitized engine preloaded)
    segv = recs["segv.stl"]["reason"]
    assert "crashed" in segv and ("exit code -11" in segv or (
        "exit code -6" in segv and "libasan" in os.environ.get("LD_PRELOAD", "")))
    assert "over the time limit of 2 s" in recs["hang.stl"]["reason"]
    ok = [r for r in recs.values() if r["status"] == "ok"]
    assert len(ok) == 9
    assert len({r["pid"] for r in ok}) <= 2 + 3  # the first two workers and the replacements


def test_mesh_boundary_counts_edges():
    """A closed bar has no boundary and no non-manifold edge; one face taken away leaves its
    3 edges on the boundary; a face doubled makes its 3 edges shared by 3 faces."""
    from batch_library import bar
    from osteon.batch import mesh_boundary

    V, F = bar()
    assert mesh_boundary(F, len(V)) == (0, 0)
    assert mesh_boundary(F[1:], len(V)) == (3, 0)
    assert mesh_boundary(np.vstack([F, F[:1]]), len(V)) == (0, 3)
    assert mesh_boundary(np.zeros((0, 3), np.int32), 0) == (0, 0)


def test_bad_settings_raise_before_reading(library):
    lib, _ = library
    with pytest.raises(ValueError, match="unknown material"):
        list(batch.run([lib], {"material": "cheese"}))
    with pytest.raises(ValueError, match="unknown batch setting"):
        list(batch.run([lib], {"force": 3}))


def test_cli_batch(library, tmp_path, capsys):
    lib, expected = library
    out = tmp_path / "cli"
    assert cli_main(["batch", str(lib), "--out", str(out), "-j", "2", "--no-png",
                     "--material", "PETG"]) == 0
    text = capsys.readouterr().out
    n_ok = sum(v == "ok" for v in expected.values())
    assert f"{len(expected)} models" in text and f"{n_ok} analysed" in text
    recs = batch.read_results(out)
    petg = materials.get("PETG").strength_mpa / materials.DEFAULT_SAFETY_FACTOR
    assert {r["allowable_stress_mpa"] for r in recs if r["status"] == "ok"} == {petg}
    assert cli_main(["batch", str(lib), "--out", str(out), "--material", "cheese"]) == 2
    assert cli_main(["batch", str(lib), "--out", str(out), "--build-direction", "0,0"]) == 2


def test_cli_dask_without_distributed_names_the_extra(library, tmp_path, monkeypatch, capsys):
    lib, _ = library
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed -> ImportError
    assert cli_main(["batch", str(lib), "--out", str(tmp_path / "o"), "--dask", "local"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "pip install distributed" in err[0]
    assert err[0].startswith("osteon: error:")


def _resume_library(root: Path, n: int):
    root.mkdir(parents=True)
    for i in range(n):
        rigged_bar(root, f"bar{i:02d}", radius=3.0 + 0.2 * i, length=50.0 + i)


def test_resume_after_kill_loses_nothing_repeats_nothing(tmp_path):
    n = 14
    lib, out = tmp_path / "lib", tmp_path / "out"
    _resume_library(lib, n)
    cmd = [sys.executable, "-m", "osteon.cli", "batch", str(lib), "--out", str(out),
           "--jobs", "1", "-q"]
    proc = subprocess.Popen(cmd, start_new_session=True)
    results = out / "results.jsonl"
    deadline = time.time() + 120
    try:
        while time.time() < deadline:
            if results.exists() and results.read_text().count("\n") >= 3:
                break
            if proc.poll() is not None:
                break
            time.sleep(0.02)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    first = [json.loads(x)["model"] for x in results.read_text().splitlines()
             if x.endswith("}")]
    assert 3 <= len(first) < n, "the run should be killed part-way"
    assert cli_main(["batch", str(lib), "--out", str(out), "--jobs", "1", "--resume", "-q"]) == 0
    text = results.read_text()
    assert text.endswith("\n")
    models = [json.loads(x)["model"] for x in text.splitlines()]
    assert len(models) == n and len(set(models)) == n  # nothing lost, nothing repeated
    assert models[: len(first)] == first
    assert all(r["status"] == "ok" for r in batch.read_results(out))


def test_dask_local_cluster_matches_pool(library):
    distributed = pytest.importorskip("distributed")
    lib, expected = library
    pool = _by_name(batch.run_all([lib], SETTINGS, workers=2))
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        assert len(client.nthreads()) == 2
        dask = _by_name(batch.run_all([lib], SETTINGS, client=client))
    assert dask.keys() == pool.keys() == expected.keys()
    for k, p in pool.items():
        d = dask[k]
        assert d["status"] == p["status"] and d["reason"] == p["reason"]
        if p["status"] == "ok":
            assert d["max_stress_mpa"] == p["max_stress_mpa"]
            assert [w["max_stress_mpa"] for w in d["bone_results"]] == [
                w["max_stress_mpa"] for w in p["bone_results"]]
            np.testing.assert_array_equal(
                [s["stress_mpa"] for s in d["section_table"]],
                [s["stress_mpa"] for s in p["section_table"]])
