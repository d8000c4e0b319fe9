"""Imported once by the process pool's fork server, so that every worker forked from it starts
with the readers and matplotlib (Agg) already imported instead of importing them per worker."""

import contextlib

from . import task  # noqa: F401

with contextlib.suppress(ImportError):
    import trimesh  # noqa: F401
with contextlib.suppress(ImportError):
    from ..plots import _mpl

    _mpl()
