"""A small model library generated on the fly for the batch tests: rigged bars (TGF + DMAT
sidecars), an unrigged bar, an open bar, and files that are not meshes. Units: mm."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from osteon.io import write_dmat, write_mesh, write_tgf
from shapes import circle, prism


def bar(length=60.0, radius=5.0, n=48, stations=31):
    """A closed round bar along +x from 0 to ``length`` mm: (vertices, faces)."""
    return prism(circle(radius, n), length, stations=stations)


def rigged_bar(folder: Path, name: str, length=60.0, radius=5.0, weights=True, ext=".obj"):
    """Write NAME.EXT + NAME.tgf (two bones along the axis) [+ NAME.dmat]; returns the mesh path."""
    V, F = bar(length, radius)
    path = folder / f"{name}{ext}"
    write_mesh(path, V, F)
    joints = np.array([[0.0, 0, 0], [length / 2, 0, 0], [length, 0, 0]])
    write_tgf(folder / f"{name}.tgf", joints, [[0, 1], [1, 2]])
    if weights:
        W = np.zeros((len(V), 2))
        W[V[:, 0] < length / 2, 0] = 1.0
        W[V[:, 0] >= length / 2, 1] = 1.0
        write_dmat(folder / f"{name}.dmat", W)
    return path


def make_library(root: Path) -> dict[str, str]:
    """A folder tree of models; returns {file name: expected status}."""
    root.mkdir(parents=True, exist_ok=True)
    sub = root / "sub" / "deeper"
    sub.mkdir(parents=True)
    expected = {}
    rigged_bar(root, "thin", radius=3.0)
    expected["thin.obj"] = "ok"
    rigged_bar(root, "thick", radius=6.0, weights=False)
    expected["thick.obj"] = "ok"
    rigged_bar(sub, "short", length=30.0, radius=4.0, ext=".ply")
    expected["short.ply"] = "ok"
    V, F = bar()
    write_mesh(root / "unrigged.stl", V, F)  # no skeleton next to it
    # rigged by osteon.auto_skeleton where it exists (issue 17), else skipped
    import osteon

    expected["unrigged.stl"] = "ok" if hasattr(osteon, "auto_skeleton") else "skipped"
    Vo, Fo = bar(radius=5.0)
    write_mesh(root / "open.obj", Vo, Fo[: len(Fo) - 40])  # one cap partly removed
    write_tgf(root / "open.tgf", [[0.0, 0, 0], [30, 0, 0], [60, 0, 0]], [[0, 1], [1, 2]])
    expected["open.obj"] = "failed"
    (root / "garbage.stl").write_bytes(bytes(range(256)) * 7)
    expected["garbage.stl"] = "failed"
    (sub / "empty.obj").write_text("# nothing here\n")
    (sub / "empty.tgf").write_text("1 0 0 0\n2 1 0 0\n#\n1 2\n#\n")
    expected["empty.obj"] = "failed"
    (root / "notes.txt").write_text("not a model\n")  # not picked up from a folder
    return expected


def crashing_task(path, settings, model_id=None):
    """The batch task, except that a model whose name has "crash" kills its worker process."""
    import os

    from osteon.batch import process_model

    if "crash" in os.path.basename(path):
        os._exit(3)
    return process_model(path, settings, model_id)


def hanging_task(path, settings, model_id=None):
    """The batch task, except that a model whose name has "hang" starts a child process
    (``sleep``), writes ``PATH.pids`` (worker pid, child pid) and spins for ever: a reader
    caught in a loop, with something it started."""
    import os
    import subprocess

    from osteon.batch import process_model

    if "hang" in os.path.basename(path):
        child = subprocess.Popen(["sleep", "600"])
        tmp = path + ".pids.tmp"
        with open(tmp, "w") as fh:
            fh.write(f"{os.getpid()} {child.pid}\n")
        os.replace(tmp, path + ".pids")
        while True:  # one core at 100 %, as the glTF joint loop did
            pass
    return process_model(path, settings, model_id)


def pid_task(path, settings, model_id=None):
    """A stand-in task that reads nothing: its record names the worker process (``pid``);
    a model named "crash…" ends its worker (os._exit), "segv…" crashes it with a segmentation
    fault, "hang…" sleeps for ever (each that model's failure, the run goes on)."""
    import ctypes
    import os
    import time

    name = os.path.basename(path)
    if name.startswith("crash"):
        os._exit(3)
    if name.startswith("segv"):
        import faulthandler

        faulthandler.disable()  # pytest's handler would print the crash's stack: expected here
        ctypes.string_at(0)
    if name.startswith("hang"):
        while True:
            time.sleep(1)
    return {"model": path, "id": model_id, "status": "ok", "reason": None, "seconds": 0.0,
            "pid": os.getpid(), "_files": {}}


def unstoppable_task(path, settings, model_id=None):
    """Spins with SIGALRM blocked: like a run in the engine's C++, which no signal handler can
    interrupt (an in-process alarm never fires); only stopping its process ends it."""
    import signal

    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGALRM})
    while True:
        pass


def hang_or_real_task(path, settings, model_id=None):
    """:func:`unstoppable_task` for a model named "hang…", the real batch task otherwise."""
    import os

    from osteon.batch import process_model

    if os.path.basename(path).startswith("hang"):
        return unstoppable_task(path, settings, model_id)
    return process_model(path, settings, model_id)
