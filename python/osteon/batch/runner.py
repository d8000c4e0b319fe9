"""Running the per-model tasks: in this process, on a local process pool, or on Dask."""

from __future__ import annotations

import os
import sys
import uuid
from collections.abc import Iterator

from .discover import ModelFile, discover
from .outputs import OutputWriter, read_results, write_summaries
from .settings import BatchSettings
from .task import process_model

DASK_MISSING = (
    "the Dask path needs the 'distributed' package (a dependency of osteon): "
    "pip install distributed"
)


def _crash_record(m: ModelFile, why: str) -> dict:
    return {"model": m.path, "id": m.id, "status": "failed", "reason": why, "seconds": 0.0,
            "_files": {}}


def _serial(models, s):
    for m in models:
        yield process_model(m.path, s, m.id)


def _pool_context():
    import multiprocessing as mp

    if sys.platform.startswith("linux"):
        # forkserver: workers are forked from a clean server that has imported osteon once
        # (no fork of a process whose engine threads are running, no re-import per worker)
        ctx = mp.get_context("forkserver")
        ctx.set_forkserver_preload(["osteon.batch._warm"])
        return ctx
    return mp.get_context("spawn")


def _pool(models, s, workers: int, task=process_model):
    """A ProcessPoolExecutor with a bounded window of models in flight. A worker that dies
    (a crash in a reader or the engine) breaks the pool: the models then in flight are re-run
    one at a time in a fresh pool, so only the one that crashes is marked failed."""
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
    from concurrent.futures.process import BrokenProcessPool

    ctx = _pool_context()
    todo = list(models)[::-1]  # a stack: pop() takes the next model
    window = 2 * workers + 2
    while todo:
        crashed: list[ModelFile] = []
        with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as ex:
            pending = {}
            while todo or pending:
                while todo and len(pending) < window:
                    m = todo.pop()
                    pending[ex.submit(task, m.path, s, m.id)] = m
                done, _ = wait(pending, return_when=FIRST_COMPLETED)
                broken = False
                for f in done:
                    m = pending.pop(f)
                    try:
                        yield f.result()
                    except BrokenProcessPool:
                        crashed.append(m)
                        broken = True
                if broken:
                    crashed.extend(pending.values())
                    pending.clear()
                    break
        for m in crashed:  # isolate: one model per fresh single-worker pool
            with ProcessPoolExecutor(max_workers=1, mp_context=ctx) as one:
                try:
                    yield one.submit(task, m.path, s, m.id).result()
                except BrokenProcessPool:
                    yield _crash_record(m, "the worker process crashed on this model")


def _dask(models, s, client):
    """Same tasks on a Dask ``distributed`` client, with a bounded window of tasks in flight."""
    try:
        from distributed import as_completed
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise RuntimeError(DASK_MISSING) from e
    threads = sum(client.nthreads().values()) or 1
    window = 2 * threads + 2
    todo = list(models)[::-1]
    pending = {}

    def submit(m):
        f = client.submit(process_model, m.path, s, m.id, pure=False,
                          key=f"osteon-batch-{m.id}-{uuid.uuid4().hex}")
        pending[f.key] = m
        return f

    ac = as_completed([submit(todo.pop()) for _ in range(min(window, len(todo)))])
    for f in ac:
        m = pending.pop(f.key)
        try:
            rec = f.result()
        except Exception as e:  # noqa: BLE001 - KilledWorker and friends: a failed model
            rec = _crash_record(m, f"Dask task failed: {type(e).__name__}: {e}")
        f.release()
        yield rec
        if todo:
            ac.add(submit(todo.pop()))


def dask_client(address: str, workers: int | None = None):
    """A ``distributed.Client`` for ``address`` ('local' starts a LocalCluster of ``workers``
    single-threaded worker processes on this machine)."""
    try:
        from distributed import Client, LocalCluster
    except ImportError as e:
        raise RuntimeError(DASK_MISSING) from e
    if address == "local":
        cluster = LocalCluster(
            n_workers=workers or os.cpu_count() or 1, threads_per_worker=1, processes=True,
            dashboard_address=None,
        )
        return Client(cluster)
    return Client(address)


def run(
    paths,
    settings=None,
    *,
    client=None,
    workers: int | None = None,
    out=None,
    resume: bool = False,
    progress: bool = False,
) -> Iterator[dict]:
    """Analyse every model named by ``paths`` (files, folders searched recursively, globs) and
    yield one record per model as it finishes (in finishing order).

    ``settings``: a :class:`BatchSettings` or a dict of its fields (mm, N, MPa).
    ``client``: a ``distributed.Client``; the tasks then run on its cluster. Otherwise
    ``workers`` processes of a local pool (default: all cores; 1 = in this process).
    ``out``: folder for the outputs (see :mod:`osteon.batch.outputs`); then ``resume=True``
    skips the models already in ``out/results.jsonl``, and ``summary.csv`` / ``summary.html``
    are written when the iterator is exhausted or closed. ``progress``: a tqdm bar on stderr.

    A record is a dict: ``model``, ``id``, ``status`` (ok / skipped / failed), ``reason``,
    ``seconds`` and, for analysed models, the report fields (``stress_ratio``, …) plus
    ``bone_count``, ``flags`` (see :func:`osteon.batch.process_model`). Bad settings raise ValueError before
    any model is read; a bad model never raises.
    """
    s = BatchSettings.from_any(settings)
    s.check()
    models = discover(paths)
    if out is None:
        s = s.replace(png=False)  # no folder for the pictures
    skip = set()
    if out is not None and resume:
        skip = {r["model"] for r in read_results(out)}
    todo = [m for m in models if m.path not in skip]
    writer = OutputWriter(out, resume=resume) if out is not None else None
    if client is not None:
        it = _dask(todo, s, client)
    else:
        n = workers if workers is not None else (os.cpu_count() or 1)
        if n < 1:
            raise ValueError(f"workers must be >= 1, got {n}")
        n = min(n, max(len(todo), 1))
        it = _serial(todo, s) if n == 1 else _pool(todo, s, n)
    bar = _bar(len(todo), len(skip & {m.path for m in models})) if progress else None
    failures = 0
    try:
        for rec in it:
            if writer is not None:
                rec = writer.write(rec)
            else:
                rec.pop("_files", None)
            if rec["status"] != "ok":
                failures += 1
            if bar is not None:
                bar.update(1)
                bar.set_postfix_str(f"failed/skipped {failures}", refresh=False)
            yield rec
    finally:
        if bar is not None:
            bar.close()
        if writer is not None:
            writer.close()
            write_summaries(out)
        it.close()


def _bar(total, resumed):
    try:
        from tqdm import tqdm
    except ImportError:
        return None
    return tqdm(
        total=total, unit="model", desc="models" + (f" ({resumed} resumed)" if resumed else ""),
        file=sys.stderr, dynamic_ncols=True, smoothing=0.1,
    )


def run_all(paths, settings=None, **kw) -> list[dict]:
    """:func:`run` to the end; the records in input order."""
    recs = {r["model"]: r for r in run(paths, settings, **kw)}
    order = [m.path for m in discover(paths)]
    return [recs[p] for p in order if p in recs]


__all__ = ["DASK_MISSING", "dask_client", "run", "run_all"]

