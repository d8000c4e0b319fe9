"""Finding the models of a batch: files, folders (recursive) and glob patterns.

A model is a file whose extension one of :mod:`osteon.io`'s readers takes (OBJ, OFF, PLY, STL,
glTF, GLB). Sidecar files (TGF, DMAT, RigNet ``_rig.txt``) are not models; the reader finds them
next to their mesh.
"""

from __future__ import annotations

import glob
import hashlib
import os
import re
from dataclasses import dataclass
from pathlib import Path

from ..io.loader import GLTF_EXTENSIONS, MESH_EXTENSIONS

#: Extensions of model files (lower case, with the dot).
MODEL_EXTENSIONS = MESH_EXTENSIONS + GLTF_EXTENSIONS

_GLOB_CHARS = re.compile(r"[*?\[]")
_UNSAFE = re.compile(r"[^A-Za-z0-9._-]+")


@dataclass(frozen=True)
class ModelFile:
    """One input model: ``path`` (absolute, the key of the model in ``results.jsonl``) and
    ``id`` (a file-name-safe name for its outputs, unique within the batch)."""

    path: str
    id: str


def is_model_file(path) -> bool:
    return Path(path).suffix.lower() in MODEL_EXTENSIONS


def _walk(folder: Path):
    for root, dirs, files in os.walk(folder, followlinks=False):
        dirs.sort()
        for name in sorted(files):
            if is_model_file(name):
                yield Path(root, name)


def discover(inputs) -> list[ModelFile]:
    """The models named by ``inputs`` (str/Path or a list of them), in a stable order.

    * a file is taken whatever its extension (an unknown format is reported by the run, not
      dropped here);
    * a folder is searched recursively for model files;
    * a pattern with ``*``, ``?`` or ``[`` is expanded (``**`` crosses folders); folders it
      matches are searched, files are kept if they are model files.

    Raises ValueError naming an input that is neither a file, a folder nor a matching pattern.
    Each model is listed once even when several inputs name it.
    """
    if isinstance(inputs, (str, os.PathLike)):
        inputs = [inputs]
    found: list[tuple[Path, str]] = []  # (absolute path, name relative to its input)
    for item in inputs:
        s = os.fspath(item)
        p = Path(s)
        if p.is_file() or (os.path.islink(s) and not p.exists()):
            # a broken link or a symlink loop is that model's failure (the run reports it)
            found.append((p, p.name))
        elif p.is_dir():
            found.extend((f, str(f.relative_to(p))) for f in _walk(p))
        elif _GLOB_CHARS.search(s):
            matches = sorted(glob.glob(s, recursive=True))
            if not matches:
                raise ValueError(f"no file matches {s!r}")
            for m in map(Path, matches):
                if m.is_dir():
                    found.extend((f, str(f.relative_to(m))) for f in _walk(m))
                elif is_model_file(m):
                    found.append((m, m.name))
        else:
            raise ValueError(f"input not found: {s}")
    seen: set[str] = set()
    unique: list[tuple[str, str]] = []
    for f, rel in found:
        try:
            key = str(f.resolve()) if f.exists() else os.path.abspath(f)
        except (OSError, RuntimeError):  # a symlink loop: keep the name, the task fails it
            key = os.path.abspath(f)
        if key not in seen:
            seen.add(key)
            unique.append((key, rel))
    ids = [_UNSAFE.sub("_", rel.replace(os.sep, "__")).strip("._") or "model" for _, rel in unique]
    counts: dict[str, int] = {}
    for i in ids:
        counts[i] = counts.get(i, 0) + 1
    out = []
    for (key, _), i in zip(unique, ids):
        if counts[i] > 1:  # same relative name under two inputs: add a stable hash of the path
            i = f"{i}-{hashlib.sha1(os.fsencode(key)).hexdigest()[:8]}"
        out.append(ModelFile(key, i))
    return out
