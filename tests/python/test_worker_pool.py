"""The engine's worker pool (cpp/src/worker_pool.cpp): threads kept between parallel_for calls.

A call finds the pool busy when another thread's analysis holds it and then starts threads of
its own; an error (a cancel) inside a pool worker ends the call and leaves the pool usable.
Either way the numbers must be those of a one-thread run, bit for bit."""

import threading
import time

import numpy as np
import osteon
from rigged_models import load

FIELDS = ("stress", "section_modulus", "section_area", "moment_arm", "vertex_stress")


def _numbers(result):
    return {k: np.asarray(getattr(result, k)) for k in FIELDS}


def _same(a, b):
    return all(np.array_equal(a[k], b[k], equal_nan=True) for k in FIELDS)


def test_concurrent_analyses_on_two_workers_equal_one_thread(data_dir):
    # Three Python threads analyse at once (the engine releases the GIL), each on two workers:
    # one holds the pool, the others start their own threads; all equal the one-thread run.
    v, f, sk, w = load("arm", height_mm=120.0)
    reference = _numbers(osteon.analyze(v, f, sk, w, interval=2.0, threads=1))
    same = []

    def work():
        for _ in range(3):
            same.append(_same(_numbers(osteon.analyze(v, f, sk, w, interval=2.0, threads=2)),
                              reference))

    threads = [threading.Thread(target=work) for _ in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert same == [True] * 9


def test_cancel_on_two_workers_leaves_the_pool_usable(data_dir):
    # A cancel from another thread while two workers cut (the cow printed 1 m tall: ~1700
    # sections) ends the run with Cancelled; the next two-worker runs (the pool's threads again)
    # equal a fresh one-thread analysis.
    v, f, sk, w = load("cow", height_mm=1000.0)
    analyzer = osteon.Analyzer(f, len(v), sk, w, interval=2.0, threads=2)
    progress = osteon.Progress()
    out = {}

    def work():
        try:
            out["result"] = analyzer.run(v, progress=progress)
        except osteon.Cancelled as e:
            out["error"] = e

    t = threading.Thread(target=work)
    t.start()
    deadline = time.perf_counter() + 60
    while progress.sections_done < 200 and t.is_alive():
        assert time.perf_counter() < deadline
        time.sleep(0.0005)
    progress.cancel()
    t.join()
    assert isinstance(out.get("error"), osteon.Cancelled), out
    small = load("arm", height_mm=120.0)
    reference = _numbers(osteon.analyze(*small, interval=2.0, threads=1))
    for _ in range(2):
        assert _same(_numbers(osteon.analyze(*small, interval=2.0, threads=2)), reference)
