"""Writing output files whole or not at all, and checking an output path before the work.

Every report, JSON, CSV, HTML, PNG and mesh the CLI and batch write goes through
:func:`write_atomic`: the bytes go to a temporary file in the same folder, which then replaces
the final name (``os.replace``, atomic on POSIX and Windows within one file system). A kill at
any moment leaves either the previous file or the new one under the final name, never a torn
one; the temporary file of a killed write is a hidden ``.NAME.*.tmp…`` beside it.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Callable
from pathlib import Path


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_atomic(path, data: bytes | str | None = None, *,
                 writer: Callable[[str], None] | None = None, encoding: str = "utf-8") -> Path:
    """Write ``data`` (bytes or str) to ``path``, or let ``writer(tmp_path)`` write the file
    (the temporary path keeps ``path``'s extension, for writers that pick the format by it),
    then move it over ``path`` in one step. Returns ``path``. Raises ValueError naming the path
    when it cannot be written (a folder, no such folder, no permission, disk full)."""
    path = Path(os.fspath(path))
    folder = path.parent if str(path.parent) else Path(".")
    check_output_path(path)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp" + path.suffix,
                                   dir=folder)
    except OSError as e:
        raise ValueError(f"{path}: cannot write here ({e.strerror or e})") from None
    try:
        if writer is None:
            raw = data.encode(encoding) if isinstance(data, str) else bytes(data or b"")
            with os.fdopen(fd, "wb") as fh:
                fh.write(raw)
                fh.flush()
                os.fsync(fh.fileno())
        else:
            os.close(fd)
            writer(tmp)
        os.chmod(tmp, 0o666 & ~_umask())  # as a plain open() would have made it
        os.replace(tmp, path)
    except OSError as e:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise ValueError(f"{path}: cannot write ({e.strerror or e})") from None
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    return path


def check_output_path(path, option: str = "") -> Path:
    """Raise ValueError (naming ``option``, e.g. ``--json``) unless ``path`` can be written:
    not a folder, its folder exists and is writable. Call it before the work, so that a long
    analysis is not lost to a typo in an output name."""
    p = Path(os.fspath(path))
    who = f"{option} {p}" if option else str(p)
    if p.is_dir():
        raise ValueError(f"{who}: is a folder; give a file name")
    folder = p.parent if str(p.parent) else Path(".")
    if not folder.is_dir():
        raise ValueError(f"{who}: the folder {folder} does not exist")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise ValueError(f"{who}: the folder {folder} is not writable")
    if p.exists() and not os.access(p, os.W_OK):
        raise ValueError(f"{who}: the file exists and is not writable")
    return p
