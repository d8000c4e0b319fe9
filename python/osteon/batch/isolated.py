"""One model at a time in a child process that a time limit can stop: the per-model time limit
of Dask runs.

A Dask worker cannot stop a task once it runs (``Future.cancel`` only forgets the result; the
thread keeps spinning, and the engine's C++ cannot be interrupted). So with a time limit each
Dask task hands its model to a long-lived child process of the Dask worker (one per worker
thread, started on its first model: a fresh interpreter, since a Dask worker has threads and is
daemonic), waits at most the limit, and over it kills the child's process group and answers
with that model's failure; the next model starts a new child. The child is the batch pool's
worker (:func:`osteon.batch.worker._worker_loop`): its own session, and it ends itself when the
Dask worker is gone. Units: s.
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
import threading

_local = threading.local()
_READY = "ready"
#: seconds a new child may take to start (a fresh interpreter importing osteon: ~1 s, more on
#: a loaded machine); not counted in the model's time limit
START_S = 120.0


class _Pipes:
    """The child's end: models in from one pipe, records out through another (``recv`` /
    ``send`` as the pool worker's connection)."""

    def __init__(self, read_fd: int, write_fd: int):
        from multiprocessing.connection import Connection

        self._in = Connection(read_fd, writable=False)
        self._out = Connection(write_fd, readable=False)

    def recv(self):
        return self._in.recv()

    def send(self, obj):
        self._out.send(obj)


class _Child:
    """A child Python process running the pool worker's loop, in its own session."""

    def __init__(self, task: str):
        from multiprocessing.connection import Connection

        job_r, job_w = os.pipe()
        rec_r, rec_w = os.pipe()
        # this process's import path, so that the child finds the task's module as we do
        env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in sys.path if p)}
        self.task = task
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "osteon.batch.isolated", str(job_r), str(rec_w),
             str(os.getpid()), task],
            pass_fds=(job_r, rec_w), start_new_session=True, stdin=subprocess.DEVNULL, env=env,
        )
        os.close(job_r)
        os.close(rec_w)
        self.ready = False
        self.jobs = Connection(job_w, readable=False)
        self.records = Connection(rec_r, writable=False)

    def stop(self):
        from .worker import _kill_group

        _kill_group(self.proc.pid)
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.proc.wait(5)
        self.jobs.close()
        self.records.close()


def run_isolated(path: str, settings, model_id: str, timeout_s: float, finish: bool,
                 task=None) -> dict:
    """The record of one model, analysed in this thread's child process; a model over
    ``timeout_s`` seconds (or one that kills the child) is that model's failure. ``task``: a
    module-level function of :func:`osteon.batch.process_model`'s signature (default that)."""
    from .discover import ModelFile
    from .worker import _crash_record, _over_time

    name = "" if task is None else f"{task.__module__}:{task.__qualname__}"
    child = getattr(_local, "child", None)
    if child is None or child.proc.poll() is not None or child.task != name:
        if child is not None:
            child.stop()
        child = _local.child = _Child(name)
    m = ModelFile(path, model_id)
    try:
        if not child.ready:
            if not (child.records.poll(START_S) and child.records.recv() == _READY):
                raise OSError("the worker process did not start")
            child.ready = True
        child.jobs.send((path, settings, model_id, finish))
        if child.records.poll(timeout_s):
            return child.records.recv()
        why = _over_time(timeout_s)
    except (EOFError, OSError):
        child.proc.poll()
        why = f"the worker process crashed on this model (exit code {child.proc.returncode})"
    child.stop()
    _local.child = None
    return _crash_record(m, why)


def _main(argv) -> None:
    import importlib

    from .task import process_model
    from .worker import _worker_loop

    job_r, rec_w, parent = (int(x) for x in argv[:3])
    task = process_model
    if len(argv) > 3 and argv[3]:
        module, name = argv[3].split(":")
        task = getattr(importlib.import_module(module), name)
    os.dup2(2, 1)  # a print in a model goes to stderr, never into the records' pipe
    pipes = _Pipes(job_r, rec_w)
    pipes.send(_READY)  # imported: the time limit of the first model starts now
    _worker_loop(pipes, task, parent)


if __name__ == "__main__":
    _main(sys.argv[1:])
