"""Progress, cancel and the section estimate (issue 20: responsive on any model)."""

import threading
import time

import numpy as np
import osteon
import pytest
from osteon.settings import SECTION_LIMIT, section_guard
from rigged_models import load

MODELS = ["arm", "cow", "rignet2982", "cheburashka"]


@pytest.mark.parametrize("name", MODELS)
def test_estimate_equals_the_engines_section_count(name, data_dir):
    # Exact, before any cut: the number of sections the analysis makes on real rigs (joint
    # rigs with several bones per joint, extra roots), at several intervals and print sizes.
    v, f, sk, w = load(name, height_mm=120.0)
    for size_mm, h in ((120.0, 2.0), (120.0, 0.7), (480.0, 2.0), (120.0, 9.0)):
        k = size_mm / 120.0
        est = osteon.estimate_sections(sk.scaled(k), interval=h)
        a = osteon.analyze(v * k, f, sk.scaled(k), w, interval=h)
        assert est == a.num_sections, (name, size_mm, h)


def test_estimate_closed_form_and_bad_input():
    # Two collinear bones of 10 mm and 25 mm at h = 3: 3 + 8 interior planes, 2 free ends,
    # 1 joint section.
    sk = osteon.Skeleton([[0, 0, 0], [10, 0, 0]], [[10, 0, 0], [35, 0, 0]], [-1, 0])
    assert osteon.estimate_sections(sk, 3.0) == 3 + 8 + 2 + 1
    # scaled x1000 (a model in metres read as mm): 1000 times the planes, same ends/joints
    assert osteon.estimate_sections(sk.scaled(1000.0), 3.0) == 3333 + 8333 + 3
    with pytest.raises(ValueError, match="interval"):
        osteon.estimate_sections(sk, 0.0)
    with pytest.raises(ValueError, match="Skeleton"):
        osteon.estimate_sections("not a skeleton", 2.0)


def test_estimate_is_fast_on_a_kilometre_model(data_dir):
    # The x1000 case of the issue: millions of sections, answered without cutting anything.
    _v, _f, sk, _w = load("cow", height_mm=2.35e6)
    t0 = time.perf_counter()
    n = osteon.estimate_sections(sk, 2.0)
    assert time.perf_counter() - t0 < 0.05
    lengths = sk.lengths
    assert n >= int(np.sum(np.ceil(lengths / 2.0) - 1))  # at least the interior planes
    assert n > 100 * SECTION_LIMIT


def test_section_guard_words_the_warning():
    assert section_guard(SECTION_LIMIT, 2.0, 120.0) is None
    msg = section_guard(2_623_469, 2.0, 2.35e6)
    assert msg == ("2 623 469 sections at 2 mm on a 2.35 km model: check the print size "
                   "(limit 20 000)")
    assert "2.45 m model" in section_guard(30_000, 0.5, 2450.0, limit=1000)
    assert "120 mm model" in section_guard(30_000, 0.01, 120.0)


def _run_and_cancel_after(analyzer, vertices, after_sections):
    """Run analyzer.run in a worker thread and cancel it once ``after_sections`` are cut;
    returns (progress, exception or result, seconds from cancel() to the worker's end)."""
    progress = osteon.Progress()
    out = {}

    def work():
        try:
            out["result"] = analyzer.run(vertices, progress=progress)
        except BaseException as e:  # noqa: BLE001 -- handed to the test
            out["error"] = e
        out["end"] = time.perf_counter()

    t = threading.Thread(target=work)
    t.start()
    deadline = time.perf_counter() + 60
    while progress.sections_done < after_sections and t.is_alive():
        assert time.perf_counter() < deadline
        time.sleep(0.0005)
    t_cancel = time.perf_counter()
    progress.cancel()
    t.join()
    return progress, out.get("error", out.get("result")), out["end"] - t_cancel


def test_cancel_from_another_thread_stops_early_and_next_run_is_clean(data_dir):
    # A long analysis (the cow printed 3 m tall: ~5000 sections) cancelled from the main thread
    # after 300 sections: Cancelled, far from the end; the same Analyzer's next run equals a
    # fresh Analyzer's (nothing half-made is reused).
    v, f, sk, w = load("cow", height_mm=3000.0)
    kw = {"interval": 2.0, "threads": 1}
    analyzer = osteon.Analyzer(f, len(v), sk, w, **kw)
    analyzer.run(v + 0.5)  # a last run on other vertices, which the cancelled run replaces
    progress, outcome, stop_s = _run_and_cancel_after(analyzer, v, 300)
    assert isinstance(outcome, osteon.Cancelled), outcome
    assert progress.cancelled
    total = osteon.estimate_sections(sk, 2.0)
    assert progress.sections_total == total
    assert 300 <= progress.sections_done < total // 2
    assert progress.runs_done == 0
    assert 0.0 < progress.fraction < 0.5
    assert stop_s < 1.0
    again = analyzer.run(v)
    fresh = osteon.Analyzer(f, len(v), sk, w, **kw).run(v)
    np.testing.assert_array_equal(again.stress, fresh.stress)
    np.testing.assert_array_equal(again.vertex_stress, fresh.vertex_stress)
    np.testing.assert_array_equal(again.moment_arm, fresh.moment_arm)


def test_progress_follows_analyze_and_correct(data_dir):
    v, f, sk, w = load("arm", height_mm=120.0)
    p = osteon.Progress()
    a = osteon.analyze(v, f, sk, w, interval=2.0, progress=p)
    assert p.sections_total == p.sections_done == a.num_sections
    assert p.runs_done == 1 and p.fraction == 1.0
    p.reset()
    c = osteon.correct(v, f, sk, w, force=200.0, interval=4.0, max_rounds=3, progress=p)
    assert p.runs_done == c.num_rounds + 2  # first analysis, one per round, the last
    p.reset()
    p.cancel()
    with pytest.raises(osteon.Cancelled):
        osteon.correct(v, f, sk, w, interval=4.0, progress=p)
    with pytest.raises(ValueError, match="progress"):
        osteon.analyze(v, f, sk, w, progress="yes")
