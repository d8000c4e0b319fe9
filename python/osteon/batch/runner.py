"""Running the per-model tasks: in this process, on a local process pool, or on Dask."""

from __future__ import annotations

import contextlib
import os
import sys
import uuid
import warnings
from collections.abc import Iterator
from pathlib import Path

from .discover import ModelFile, discover
from .outputs import (
    OutputWriter,
    check_resume_settings,
    finish_record,
    read_results,
    save_settings,
    write_summaries,
)
from .settings import BatchSettings
from .task import process_model
from .worker import _crash_record, _kill_group, _over_time, _worker_loop

DASK_MISSING = (
    "the Dask path needs the 'distributed' package (a dependency of osteon): "
    "pip install distributed"
)


def _serial(models, s):
    """In this process, one model after the other (no time limit: a limit needs a process it
    can stop, see :func:`run`)."""
    for m in models:
        yield process_model(m.path, s, m.id)


def _forkable() -> bool:
    """True when a worker may be forked from this process (Linux, one Python thread).

    Forking copies a process whose only running thread is the caller, so no lock can be left
    held by another thread; the engine starts its threads inside a call and joins them before
    returning, and OpenBLAS's idle threads are stopped and restarted around ``fork`` by its own
    ``pthread_atfork`` handlers. A forked worker starts in milliseconds with everything this
    process imported (a fresh interpreter importing osteon costs ~1 s of CPU, as much as
    ~30 models). Any other Python thread (a progress bar's monitor, a Dask client, a caller's
    threads): the fork server instead."""
    import threading

    return (sys.platform.startswith("linux") and threading.active_count() == 1
            and "fork" in _mp().get_all_start_methods())


def _mp():
    import multiprocessing as mp

    return mp


def _pool_context(fork: bool):
    mp = _mp()
    if fork:
        for stream in (sys.stdout, sys.stderr):  # a child must not write our buffers again
            with contextlib.suppress(Exception):
                stream.flush()
        return mp.get_context("fork")
    if sys.platform.startswith("linux"):
        # forkserver: workers are forked from a clean server that has imported osteon once
        # (no fork of a process whose engine threads are running, no re-import per worker)
        ctx = mp.get_context("forkserver")
        ctx.set_forkserver_preload(["osteon.batch._warm"])
        return ctx
    return mp.get_context("spawn")


def _preload(s) -> None:
    """Import in this process what every worker needs, before forking them, so that it is
    imported once (matplotlib when pictures are drawn; the readers are imported already).
    trimesh (glTF, unusual mesh layouts) stays lazy: a worker imports it if a model needs it."""
    from . import task  # noqa: F401

    if s.png:
        with contextlib.suppress(ImportError):
            from ..plots import _mpl

            _mpl()


class _Worker:
    """One long-lived worker process (started once, then given models one by one through a
    pipe) and the model it works on (``deadline``: when it is over time)."""

    def __init__(self, ctx, task):
        self.conn, child = ctx.Pipe()
        self.proc = ctx.Process(target=_worker_loop, args=(child, task, os.getpid()),
                                daemon=True)
        with warnings.catch_warnings():
            # Python >= 3.12 warns on fork when the process has other OS threads: here only
            # OpenBLAS's idle ones, which its pthread_atfork handlers take care of (_forkable)
            warnings.filterwarnings("ignore", message=r".*use of fork\(\) may lead to deadlocks",
                                    category=DeprecationWarning)
            self.proc.start()
        child.close()
        self.model: ModelFile | None = None
        self.deadline: float | None = None

    def give(self, m: ModelFile, s, timeout, finish: bool):
        import time

        self.model = m
        self.deadline = time.monotonic() + timeout if timeout else None
        self.conn.send((m.path, s, m.id, finish))

    def stop(self):
        """Kill the worker and its process group; wait for it."""
        if self.proc.pid is not None:
            _kill_group(self.proc.pid)
        self.proc.join(5)
        self.conn.close()

    def close(self):
        """Ask an idle worker to leave; kill it if it does not."""
        with contextlib.suppress(OSError, ValueError):
            self.conn.send(None)
        self.proc.join(2)
        if self.proc.is_alive():
            self.stop()
        else:
            self.conn.close()


def _pool(models, s, workers: int, task=process_model, timeout=None, finish=False):
    """``workers`` long-lived worker processes, started now (before the caller starts any
    thread: they are forked from this process when :func:`_forkable`), each given one model at
    a time; returns the iterator of records. A worker that dies (a crash in a reader or the
    engine) fails only its model; a model over ``timeout`` seconds is that model's failure: its
    worker's process group is killed and a fresh worker takes over. When the run ends or is
    stopped, every worker is ended (no orphan process). ``finish``: the workers return records
    as :func:`osteon.batch.outputs.finish_record` makes them (for an output folder)."""
    todo = list(models)[::-1]  # a stack: pop() takes the next model
    if not todo:
        return (rec for rec in ())  # a generator: the caller closes it
    fork = _forkable()
    if fork:
        _preload(s)
    ctx = _pool_context(fork)
    idle = [_Worker(ctx, task) for _ in range(min(workers, len(todo)))]

    def fresh():
        # a replacement: forked again while this process still has one thread (a progress
        # bar's monitor thread may have started since), else from the fork server
        nonlocal ctx, fork
        if fork and not _forkable():
            fork, ctx = False, _pool_context(False)
        return _Worker(_pool_context(True) if fork else ctx, task)

    return _pool_loop(todo, idle, fresh, s, timeout, finish)


def _pool_loop(todo, idle, fresh, s, timeout, finish):
    import time
    from multiprocessing.connection import wait

    busy: dict = {}
    try:
        while todo or busy:
            while todo and idle:
                w = idle.pop()
                w.give(todo.pop(), s, timeout, finish)
                busy[w.conn] = w
            deadlines = [w.deadline for w in busy.values() if w.deadline is not None]
            wait_s = max(0.0, min(deadlines) - time.monotonic()) if deadlines else None
            for conn in wait(list(busy), timeout=wait_s):
                w = busy.pop(conn)
                try:
                    rec = conn.recv()
                except (EOFError, OSError):
                    w.proc.join(1)
                    rec = _crash_record(w.model, "the worker process crashed on this model "
                                        f"(exit code {w.proc.exitcode})")
                    w.stop()
                    w = fresh() if todo else None
                if w is not None:
                    idle.append(w)
                yield rec
            now = time.monotonic()
            for conn, w in list(busy.items()):
                if w.deadline is not None and now >= w.deadline:
                    del busy[conn]
                    w.stop()
                    if todo:
                        idle.append(fresh())
                    yield _crash_record(w.model, _over_time(timeout))
    finally:
        for w in list(busy.values()):
            w.stop()
        for w in idle:
            w.close()


def _dask_task(path, s, model_id, finish, timeout, task=None):
    """The task of a Dask run: :func:`process_model` (or ``task``; with ``finish``: the record
    as the output folder keeps it); with a time limit in a child process that can be stopped
    (:mod:`osteon.batch.isolated`)."""
    if timeout:
        from .isolated import run_isolated

        return run_isolated(path, s, model_id, timeout, finish, task)
    rec = (task or process_model)(path, s, model_id)
    return finish_record(rec) if finish else rec


def _dask(models, s, client, finish=False, timeout=None, task=None):
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
        f = client.submit(_dask_task, m.path, s, m.id, finish, timeout, task, pure=False,
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
    ``workers`` long-lived processes of a local pool (default: all cores). The settings'
    ``model_timeout_s`` holds for every runner: with ``workers=1`` the models run in one worker
    process (in this process when the limit is 0), on Dask each in a child process of the Dask
    worker (:mod:`osteon.batch.isolated`).
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
    if out is not None:
        if Path(out).exists() and not Path(out).is_dir():
            raise ValueError(f"--out {out}: is a file; give a folder")
        if resume:
            check_resume_settings(out, s)
            skip = {r["model"] for r in read_results(out)}
    todo = [m for m in models if m.path not in skip]
    finish = out is not None  # records as the output folder keeps them, made by the workers
    timeout = s.model_timeout_s or None
    if client is not None:
        it = _dask(todo, s, client, finish, timeout)
    else:
        n = workers if workers is not None else (os.cpu_count() or 1)
        if n < 1:
            raise ValueError(f"workers must be >= 1, got {n}")
        n = min(n, max(len(todo), 1))
        # the pool starts here, before the output file and the progress bar (a thread) exist;
        # one model at a time with a time limit is a pool of one worker (only a process can be
        # stopped in the engine's C++); without a limit it runs in this process
        it = (_serial(todo, s) if n == 1 and timeout is None
              else _pool(todo, s, n, task=process_model, timeout=timeout, finish=finish))
    writer = OutputWriter(out, resume=resume) if out is not None else None
    if writer is not None:
        save_settings(out, s)
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

