"""The worker process of a batch: what it runs, how it is stopped, and the records of models
it could not finish. Shared by the local pool (:mod:`osteon.batch.runner`) and the Dask time
limit (:mod:`osteon.batch.isolated`)."""

from __future__ import annotations

import contextlib
import os
import signal

from .discover import ModelFile
from .outputs import finish_record


def _crash_record(m: ModelFile, why: str) -> dict:
    return {"model": m.path, "id": m.id, "status": "failed", "reason": why, "seconds": 0.0,
            "_files": {}}


def _over_time(timeout) -> str:
    return (f"stopped: over the time limit of {timeout:g} s per model (model_timeout_s, "
            "--model-timeout)")


def _watch_parent(parent_pid: int):
    """In a worker: end the worker's process group when the batch process is gone (killed),
    so that no worker keeps spinning on a model nobody waits for."""
    import threading
    import time

    forked = os.getppid() == parent_pid  # forked by the batch process itself

    def gone() -> bool:
        if forked and os.getppid() != parent_pid:  # reparented: the batch process died
            return True
        try:
            os.kill(parent_pid, 0)
        except ProcessLookupError:
            return True
        except PermissionError:  # pid reused by another user's process: ours is gone
            return True
        return False

    def watch():
        while True:
            time.sleep(0.5)
            if gone():
                _kill_group(os.getpid())
                os._exit(1)

    threading.Thread(target=watch, daemon=True).start()


def _worker_loop(conn, task, parent_pid):
    """A pool worker: its own process group (so that stopping it stops whatever it started),
    then models from ``conn`` one by one until None or EOF, each result sent back (with
    ``finish``: as the output folder keeps it, its JSON report already serialised, so that the
    batch process only writes bytes)."""
    with contextlib.suppress(OSError):
        os.setsid()
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl+C is the batch process's to handle
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    _watch_parent(parent_pid)
    while True:
        try:
            job = conn.recv()
        except (EOFError, OSError):
            return
        if job is None:
            return
        path, s, model_id, finish = job
        try:
            rec = task(path, s, model_id)
            if finish:
                rec = finish_record(rec)
        except Exception as e:  # noqa: BLE001 - process_model never raises; a test task may
            rec = {"model": path, "id": model_id, "status": "failed",
                   "reason": f"{type(e).__name__}: {e}", "seconds": 0.0, "_files": {}}
        conn.send(rec)


def _kill_group(pid: int):
    """SIGKILL the process group led by ``pid`` (a worker after its setsid), then ``pid``."""
    if os.name != "posix":
        return
    with contextlib.suppress(ProcessLookupError, PermissionError):
        if os.getpgid(pid) == pid:
            os.killpg(pid, signal.SIGKILL)
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.kill(pid, signal.SIGKILL)
