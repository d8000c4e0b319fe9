"""Issue 36: every file a user brings gives a model, a warning in words, or one line naming the
file and the problem — never a traceback, a hang or a silent loss. The catalogue of bad files is
generated at test time by ``bad_inputs.py``. Units: mm, N, MPa."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from bad_inputs import CASES, build
from batch_library import rigged_bar
from osteon import batch
from osteon.cli import main as cli_main
from osteon.io import load_model

HERE = Path(__file__).resolve().parent
SETTINGS = {"force_n": 20.0, "material": "PLA", "png": False}


# --- the catalogue, through the reader and through the command line ------------------------

@pytest.mark.parametrize("name", sorted(CASES))
def test_reader_gives_a_model_or_names_the_problem(name, tmp_path):
    _, kind, expected = CASES[name]
    path = build(tmp_path, name)
    if kind == "error":
        with pytest.raises(ValueError, match=expected) as exc:
            load_model(path)
        assert Path(path).name.split(".")[0] in str(exc.value)  # the message names the file
        return
    m = load_model(path)
    assert all(n.encode("utf-8") for n in m.bone_names)  # names the engine and JSON take
    if kind == "warning":
        assert any(re.search(expected, w) for w in m.warnings), m.warnings
    else:
        assert m.warnings == []


@pytest.mark.parametrize("name", sorted(n for n, c in CASES.items() if c[1] != "ok"))
def test_cli_says_it_in_one_line(name, tmp_path, capsys):
    _, kind, expected = CASES[name]
    path = build(tmp_path, name)
    rc = cli_main(["analyze", str(path), "--force", "20", "-q" if kind == "error" else "--top=3"])
    err = capsys.readouterr().err
    if kind == "error":
        assert rc == 2
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("osteon: error: "), err
        assert re.search(expected, lines[0])
        assert "Traceback" not in err
    else:
        assert rc == 0
        assert re.search(expected, err) and "osteon: warning:" in err


def test_rignet_without_skin_keeps_every_bone(tmp_path):
    """The 8-bone rig analysed as 1 bone, silently: now all bones stay, with a warning."""
    m_skin = load_model(build(tmp_path, "good_bar"))
    m = load_model(build(tmp_path, "rignet_without_skin_lines"))
    assert m.n_bones == m_skin.n_bones == 2 and m.weights is None


def test_json_report_keeps_the_readers_warnings(tmp_path):
    import json

    path = build(tmp_path, "dmat_bone_without_weight")
    js = tmp_path / "r.json"
    assert cli_main(["analyze", str(path), "--json", str(js), "-q"]) == 0
    rep = json.loads(js.read_text())
    assert any("without any weight" in w and "bone_1" in w for w in rep["warnings"])


def test_validate_reports_what_the_weights_held(tmp_path, capsys):
    path = build(tmp_path, "dmat_nan_negative_7_3")
    assert cli_main(["validate", str(path)]) == 0
    out = capsys.readouterr().out
    assert re.search(r"weight_rows_sum_to_1\s+False", out)
    assert re.search(r"weights_in_file\s+5 NaN/inf entries set to 0; 3 negative entries set "
                     r"to 0; 12 rows summed to 7\.3 \.\. 7\.3, rescaled to 1", out)
    good = build(tmp_path, "good_bar")
    assert cli_main(["validate", str(good)]) == 0
    out = capsys.readouterr().out
    assert re.search(r"weight_rows_sum_to_1\s+True", out)
    assert "clean (every weighted row sums to 1)" in out


# --- output paths, names, packages, absurd numbers ----------------------------------------

def test_output_paths_are_checked_before_the_work(tmp_path, capsys):
    path = rigged_bar(tmp_path, "bar")
    folder = tmp_path / "a_folder"
    folder.mkdir()
    for opt, value, msg in [("--json", folder, "is a folder"),
                            ("--png", tmp_path / "nowhere" / "p.png",
                             f"the folder {tmp_path / 'nowhere'} does not exist")]:
        t = time.perf_counter()
        assert cli_main(["analyze", str(path), opt, str(value)]) == 2
        captured = capsys.readouterr()
        assert captured.out == ""  # refused before the analysis printed anything
        assert f"osteon: error: {opt} {value}: {msg}" in captured.err
        assert time.perf_counter() - t < 5
    assert cli_main(["correct", str(path), "--out", str(folder)]) == 2
    assert "use an .obj" in capsys.readouterr().err


def test_non_utf8_model_name_with_png(tmp_path, capsys):
    raw = os.fsencode(tmp_path) + b"/bar\xff"
    rigged_bar(tmp_path, "tmp")
    for ext in (".obj", ".tgf", ".dmat"):
        os.rename(tmp_path / f"tmp{ext}", os.fsdecode(raw + ext.encode()))
    png = tmp_path / "p.png"
    assert cli_main(["analyze", os.fsdecode(raw + b".obj"), "--png", str(png)]) == 0
    assert "bar\ufffd.obj" in capsys.readouterr().out
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_missing_optional_package_is_named(tmp_path, monkeypatch, capsys):
    path = rigged_bar(tmp_path, "bar")
    with open(path, "a") as fh:  # a continued line: a layout left to trimesh
        fh.write("# a comment \\\n continued\n")
    monkeypatch.setitem(sys.modules, "trimesh", None)  # import trimesh -> ModuleNotFoundError
    assert cli_main(["analyze", str(path)]) == 2
    err = capsys.readouterr().err
    assert "needs the Python package 'trimesh' (pip install trimesh)" in err


def test_absurd_force_is_an_error_not_inf(tmp_path, capsys):
    path = rigged_bar(tmp_path, "bar")
    assert cli_main(["analyze", str(path), "--force", "1e308"]) == 2
    assert re.search(r"--force 1e\+308 N: \d+ of \d+ section stresses overflow \(inf\)",
                     capsys.readouterr().err)


def test_json_bone_rows_leave_too_thin_sections_out():
    """A bar 0.5 mm thick over its first 20 mm (under the 0.8 mm printable minimum), 10 mm
    after. The engine leaves the thin sections out of the max stress; the JSON bone rows (one
    builder for the CLI table, batch and add-on: osteon.report) must too, else the thin bone's
    row shows a stress far above the headline's maximum (the rows used the raw stresses)."""
    import osteon
    from osteon.report import build_report
    from shapes import revolve

    xs = [0.0, 19.9, 20.1, 60.0]
    v, f = revolve(xs, [0.25, 0.25, 5.0, 5.0])
    sk = osteon.Skeleton([[0, 0, 0], [30, 0, 0]], [[30, 0, 0], [60, 0, 0]], [-1, 0])
    a = osteon.analyze(v, f, sk, None, force=20.0, min_thickness=0.8)
    thin = (a.section_flags & osteon.SECTION_FLAGS["too_thin"]) != 0
    assert thin.any() and (~thin).any()
    assert np.nanmax(np.where(thin, a.stress, np.nan)) > 10 * a.max_stress  # what rows showed
    rep = build_report(analysis=a, bone_names=["thin", "thick"], allowable_mpa=60.0,
                       settings={"force_n": 20.0}, front_end="test", model="bar")
    expected = np.where(thin, np.nan, a.stress)
    for row in rep["bones"]:
        on = a.section_bone == row["index"]
        assert row["max_stress_mpa"] == pytest.approx(np.nanmax(expected[on]))
        assert row["max_stress_mpa"] <= rep["max_stress_mpa"] * (1 + 1e-12)
    assert rep["worst"]["stress_mpa"] == pytest.approx(rep["max_stress_mpa"])
    # the doubt of the maximum is the doubt of the section that gives it, not a thin one's
    assert "too_thin" not in rep["max_stress_doubt"]
    assert len(rep["too_thin_sections"]) == int(thin.sum())  # listed apart


def test_tiny_model_headline_agrees_with_rows(tmp_path, capsys):
    """0.12 mm tall: every section too thin. The engine leaves them out of the max stress
    ("0.00 MPa, 0 weak"); the rows said WEAK at 1e6 MPa. Now neither counts them."""
    path = rigged_bar(tmp_path, "bar")
    assert cli_main(["analyze", str(path), "--height-mm", "0.12"]) == 0
    out = capsys.readouterr().out
    assert "no printable section (all too thin): no max stress" in out
    assert "WEAK" not in out
    assert re.search(r"(\d+) too thin to print \(not counted, listed below\)", out)


def test_model_read_far_too_big_is_refused_quickly(tmp_path, capsys):
    path = rigged_bar(tmp_path, "bar")
    t = time.perf_counter()
    assert cli_main(["analyze", str(path), "--height-mm", "120000", "--interval", "0.1"]) == 2
    err = capsys.readouterr().err
    assert time.perf_counter() - t < 10
    m = re.search(r"refused: ([\d ]+) sections \(~([\d.]+) GB of memory\) at 0\.1 mm on a "
                  r"120 m model: above the limit of 200 000 sections", err)
    assert m, err
    assert int(m.group(1).replace(" ", "")) > 1_000_000  # 2 bones of 60 m at 0.1 mm
    assert cli_main(["analyze", str(path), "--max-sections", "10"]) == 2
    assert "above the limit of 10 sections" in capsys.readouterr().err
    assert cli_main(["analyze", str(path), "--max-sections", "100", "-q"]) == 0


# --- batch: never stops, never hangs, leaves nothing behind -----------------------------

def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state not in ("Z", "X")


def _wait_dead(pids, seconds=10.0) -> list[int]:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        left = [p for p in pids if _alive(p)]
        if not left:
            return []
        time.sleep(0.1)
    return [p for p in pids if _alive(p)]


def _library_with_catalogue(root: Path) -> dict[str, str]:
    """Good bars, the whole catalogue, a symlink loop, a broken link and a non-UTF-8 name;
    returns {file name: expected reason regex or "ok"}."""
    root.mkdir()
    expected = {}
    for i in range(2):
        rigged_bar(root, f"good{i}")
        expected[f"good{i}.obj"] = "ok"
    for name, (_, kind, msg) in CASES.items():
        p = build(root, name)
        expected[Path(p).name] = msg if kind == "error" else "ok"
    os.symlink("loop_b.obj", root / "loop_a.obj")
    os.symlink("loop_a.obj", root / "loop_b.obj")
    expected["loop_a.obj"] = expected["loop_b.obj"] = r"unreadable: .*(symbolic links|not found)"
    os.symlink("nothing_here.obj", root / "broken.obj")
    expected["broken.obj"] = "unreadable: .*not found"
    rigged_bar(root, "tmpname")
    for ext in (".obj", ".tgf", ".dmat"):
        os.rename(root / f"tmpname{ext}", os.fsencode(root) + b"/odd\xfe" + ext.encode())
    expected["odd\udcfe.obj"] = "ok"
    return expected


def test_batch_over_the_catalogue_finishes_and_names_every_bad_file(tmp_path):
    expected = _library_with_catalogue(tmp_path / "lib")
    out = tmp_path / "out"
    recs = batch.run_all([tmp_path / "lib"], SETTINGS, workers=2, out=out)
    got = {Path(r["model"]).name: r for r in recs}
    assert set(got) == set(expected)
    for name, want in expected.items():
        r = got[name]
        if want == "ok":
            assert r["status"] == "ok", (name, r["reason"])
        else:
            assert r["status"] == "failed" and re.search(want, r["reason"]), (name, r["reason"])
    assert any("NaN/inf" in w for w in got["dmat_nan_negative_7_3.obj"]["warnings"])
    html = (out / "summary.html").read_text(encoding="utf-8")
    csv = (out / "summary.csv").read_text(encoding="utf-8")
    assert "odd\ufffd.obj" in html and "odd\ufffd.obj" in csv
    assert "gltf_joint_chain_cycle" in html and "cycle" in csv
    assert not list(out.rglob(".*.tmp*"))  # no temporary file left


def test_a_hanging_model_is_stopped_and_leaves_no_process(tmp_path):
    from batch_library import hanging_task
    from osteon.batch.runner import _pool

    lib = tmp_path / "lib"
    lib.mkdir()
    rigged_bar(lib, "good")
    hang = rigged_bar(lib, "hang")
    s = batch.BatchSettings.from_any(SETTINGS)
    t = time.perf_counter()
    recs = {Path(r["model"]).name: r for r in
            _pool(batch.discover([lib]), s, 2, task=hanging_task, timeout=3.0)}
    assert time.perf_counter() - t < 60
    assert recs["good.obj"]["status"] == "ok"
    assert recs["hang.obj"]["status"] == "failed"
    assert "over the time limit of 3 s per model" in recs["hang.obj"]["reason"]
    pids = [int(x) for x in Path(str(hang) + ".pids").read_text().split()]
    assert _wait_dead(pids) == [], "worker or its child still running"


def test_killing_the_batch_leaves_no_worker_behind(tmp_path):
    lib = tmp_path / "lib"
    lib.mkdir()
    hang = rigged_bar(lib, "hang")
    script = (
        "import sys\n"
        f"sys.path.insert(0, {str(HERE)!r})\n"
        "from batch_library import hanging_task\n"
        "from osteon import batch\n"
        "from osteon.batch.runner import _pool\n"
        "s = batch.BatchSettings.from_any({'png': False})\n"
        f"for r in _pool(batch.discover([{str(lib)!r}]), s, 2, task=hanging_task):\n"
        "    print(r['status'], flush=True)\n"
    )
    proc = subprocess.Popen([sys.executable, "-c", script])
    pids_file = Path(str(hang) + ".pids")
    end = time.monotonic() + 60
    while not pids_file.exists() and time.monotonic() < end:
        time.sleep(0.1)
    assert pids_file.exists(), "the hanging model never started"
    pids = [int(x) for x in pids_file.read_text().split()]
    server = int(Path(f"/proc/{pids[0]}/stat").read_text().rsplit(")", 1)[1].split()[1])
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert _wait_dead(pids + [server]) == [], "a worker, its child or the fork server survived"


def test_dask_time_limit_stops_a_hanging_model(tmp_path):
    """Dask cannot stop a running task; with a time limit each task runs its model in a child
    process of the Dask worker (osteon.batch.isolated): the hanging model fails with the
    limit's reason, the child and what it started are killed, the next model is analysed."""
    distributed = pytest.importorskip("distributed")
    from batch_library import hanging_task
    from osteon.batch.runner import _dask

    lib = tmp_path / "lib"
    lib.mkdir()
    hang = rigged_bar(lib, "a_hang")
    rigged_bar(lib, "b_good")
    s = batch.BatchSettings.from_any(SETTINGS)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        recs = {Path(r["model"]).stem: r for r in
                _dask(batch.discover([lib]), s, client, timeout=3.0, task=hanging_task)}
    assert recs["a_hang"]["status"] == "failed"
    assert "over the time limit of 3 s per model" in recs["a_hang"]["reason"]
    assert recs["b_good"]["status"] == "ok", recs["b_good"]["reason"]
    pids = [int(x) for x in Path(str(hang) + ".pids").read_text().split()]
    assert _wait_dead(pids) == [], "the child or what it started is still running"


def test_one_process_batch_stops_a_hang_the_alarm_cannot(tmp_path, monkeypatch):
    """-j 1 with a time limit runs the models in one worker process: a model that no signal
    handler can interrupt (the engine's C++, here a loop with SIGALRM blocked) is stopped at
    the limit and the run goes on (an in-process alarm hung here for ever)."""
    from batch_library import hang_or_real_task
    from osteon.batch import runner

    rigged_bar(tmp_path, "hang")
    rigged_bar(tmp_path, "ok")
    monkeypatch.setattr(runner, "process_model", hang_or_real_task)
    recs = {Path(r["model"]).stem: r for r in batch.run_all(
        [tmp_path], {**SETTINGS, "model_timeout_s": 1.0}, workers=1)}
    assert recs["hang"]["status"] == "failed"
    assert "over the time limit of 1 s" in recs["hang"]["reason"]
    assert recs["ok"]["status"] == "ok"


def test_resume_with_other_settings_is_refused(tmp_path):
    (tmp_path / "lib").mkdir()
    rigged_bar(tmp_path / "lib", "bar")
    out = tmp_path / "out"
    assert batch.run_all([tmp_path / "lib"], SETTINGS, workers=1, out=out)[0]["status"] == "ok"
    with pytest.raises(ValueError, match=r"--resume: .* other settings \(force_n 20.0 -> 30.0\)"):
        batch.run_all([tmp_path / "lib"], {**SETTINGS, "force_n": 30.0}, workers=1, out=out,
                      resume=True)
    # what changes no result may change (pictures, time limit)
    batch.run_all([tmp_path / "lib"], {**SETTINGS, "model_timeout_s": 9.0}, workers=1, out=out,
                  resume=True)


def test_batch_refuses_a_model_over_the_section_budget(tmp_path):
    rigged_bar(tmp_path, "bar")
    (r,) = batch.run_all([tmp_path], {**SETTINGS, "max_sections": 10}, workers=1)
    assert r["status"] == "failed"
    assert re.search(r"refused: \d+ sections \(~[\d.]+ GB of memory\) .* above the limit of 10",
                     r["reason"])


def test_api_refuses_a_run_over_the_section_budget():
    """The global budget is an analysis option (AnalysisOptions.max_sections, default the CLI's
    200 000): analyze, Analyzer and correct refuse before any work, with the message of the
    CLI and batch (the estimate, its memory at 11.2 kB per section, the setting to raise)."""
    import osteon
    from batch_library import bar
    from osteon.options import MAX_SECTIONS, AnalysisOptions

    assert AnalysisOptions().max_sections == MAX_SECTIONS == 200_000
    V, F = bar()  # 60 mm along x
    sk = osteon.Skeleton([[0, 0, 0], [30, 0, 0]], [[30, 0, 0], [60, 0, 0]], [-1, 0])
    n = osteon.estimate_sections(sk, 2.0)
    gb = (n * 11_200 + len(V) * 200) / 1e9
    msg = (rf"refused: {n} sections \(~{gb:.1f} GB of memory\) at 2 mm on a 60 mm model: "
           rf"above the limit of {n - 1} sections \(check the print size, or raise max_sections\)")
    with pytest.raises(ValueError, match=msg):
        osteon.analyze(V, F, sk, max_sections=n - 1)
    with pytest.raises(ValueError, match=msg):
        osteon.Analyzer(F, len(V), sk, max_sections=n - 1).run(V)
    with pytest.raises(ValueError, match=msg):
        osteon.correct(V, F, sk, None, max_sections=n - 1)
    assert osteon.analyze(V, F, sk, max_sections=n).num_sections == n  # at the limit: runs
    # the default: a model in metres read as mm (60 m, 2 x 15 000 sections at 2 mm: allowed;
    # 600 m: 300 000, refused)
    big = 10_000.0
    n_big = osteon.estimate_sections(sk.scaled(big), 2.0)
    assert n_big > 200_000 > osteon.estimate_sections(sk.scaled(big / 10), 2.0)
    assert osteon.analyze(V * 1000.0, F, sk.scaled(1000.0)).num_sections > 20_000
    with pytest.raises(ValueError, match=rf"refused: {n_big // 1000} {n_big % 1000:03d} sections "
                       r".* on a 600 m model: above the limit of 200 000 sections"):
        osteon.analyze(V * big, F, sk.scaled(big))
    for bad in (0, -1, 1.5, True, "many"):
        with pytest.raises(ValueError, match="max_sections must be an integer"):
            AnalysisOptions(max_sections=bad)


# --- atomic outputs --------------------------------------------------------------------

def test_a_failed_write_keeps_the_previous_file(tmp_path):
    from osteon.io.atomic import write_atomic

    target = tmp_path / "report.json"
    write_atomic(target, '{"old": 1}')

    def torn(tmp):
        Path(tmp).write_text('{"new": ')
        raise RuntimeError("killed")

    with pytest.raises(RuntimeError):
        write_atomic(target, writer=torn)
    assert target.read_text() == '{"old": 1}'
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report.json"]


def test_a_kill_while_writing_keeps_the_previous_report(tmp_path):
    target = tmp_path / "report.json"
    target.write_text('{"old": 1}')
    code = (
        "import os, signal\n"
        "from osteon.io.atomic import write_atomic\n"
        "def half(tmp):\n"
        "    open(tmp, 'w').write('{\"new\": [' + '1,' * 100000)\n"
        "    os.kill(os.getpid(), signal.SIGKILL)\n"
        f"write_atomic({str(target)!r}, writer=half)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], check=False)
    assert done.returncode == -signal.SIGKILL
    assert target.read_text() == '{"old": 1}'


def test_cli_json_is_written_whole(tmp_path):
    path = rigged_bar(tmp_path, "bar")
    js = tmp_path / "r.json"
    assert cli_main(["analyze", str(path), "--json", str(js), "-q"]) == 0
    import json

    rep = json.loads(js.read_text())
    assert np.isfinite(rep["max_stress_mpa"])
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


@pytest.mark.parametrize("error, words", [
    (np.linalg.LinAlgError("Singular matrix"), "a transform that cannot be inverted"),
    (RuntimeError("QH6154 Qhull precision error: initial simplex is flat"),
     "the points are flat or degenerate"),
    (ValueError("cannot reshape array of size 5 into shape (3)"),
     "the numbers do not fill whole rows"),
])
def test_cryptic_messages_in_plain_words_naming_the_file(error, words, tmp_path, monkeypatch,
                                                         capsys):
    import osteon

    path = rigged_bar(tmp_path, "bar")

    def fail(*a, **k):
        raise error

    monkeypatch.setattr(osteon, "analyze", fail)
    assert cli_main(["analyze", str(path), "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"osteon: error: {path}: {words}" + err.split(words, 1)[1]
    assert len(err.splitlines()) == 1


def _descendants(pid: int) -> list[int]:
    """Every process below ``pid`` (by /proc parent links)."""
    parent = {}
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                parent[int(d.name)] = int((d / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        kids = [c for c, pp in parent.items() if pp == p]
        out += kids
        todo += kids
    return out


def test_cli_batch_killed_then_resumed_over_the_catalogue(tmp_path):
    """``osteon batch`` over good files and the catalogue, killed (-9) while it works: no
    process of it is left; ``--resume`` finishes, and the summary lists every file."""
    expected = _library_with_catalogue(tmp_path / "lib")
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "osteon.cli", "batch", str(tmp_path / "lib"), "--out", str(out),
           "-j", "2", "--no-png", "-q"]
    proc = subprocess.Popen(cmd)
    results = out / "results.jsonl"
    end = time.monotonic() + 120
    while time.monotonic() < end and not (results.exists() and results.read_text().count("\n")):
        time.sleep(0.05)
    below = _descendants(proc.pid)
    assert below, "no worker started"
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert _wait_dead(below) == [], "a worker or the fork server survived the kill"
    done = subprocess.run(cmd + ["--resume"], check=False, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    recs = {Path(r["model"]).name: r for r in batch.read_results(out)}
    assert set(recs) == set(expected)
    csv = (out / "summary.csv").read_text(encoding="utf-8")
    for name, want in expected.items():
        if want != "ok":
            assert recs[name]["status"] == "failed" and re.search(want, recs[name]["reason"])
        assert name.replace("\udcfe", "\ufffd") in csv
