"""Whole model libraries: ``osteon.batch.run`` and the ``osteon batch`` command.

>>> from osteon import batch
>>> for rec in batch.run(["library/"], {"force_n": 20, "material": "PLA"}, out="report"):
...     print(rec["id"], rec["status"], rec.get("stress_ratio"))

Each model is one task (:func:`process_model`) that takes a path and returns a record; tasks run
on a local pool of long-lived worker processes (all cores by default; :mod:`.worker`), in this
process (one worker and no time limit) or on a Dask ``distributed`` cluster (``client=``; the
time limit through :mod:`.isolated`). Bad files get ``status`` / ``reason`` and never stop the
run. Outputs: :mod:`osteon.batch.outputs`. Units: mm, N, MPa.
"""

from .discover import MODEL_EXTENSIONS, ModelFile, discover
from .outputs import read_results, write_summaries
from .runner import DASK_MISSING, dask_client, run, run_all
from .settings import BatchSettings
from .task import NO_SKELETON, STATUSES, mesh_boundary, process_model

__all__ = [
    "DASK_MISSING",
    "MODEL_EXTENSIONS",
    "NO_SKELETON",
    "STATUSES",
    "BatchSettings",
    "ModelFile",
    "dask_client",
    "discover",
    "mesh_boundary",
    "process_model",
    "read_results",
    "run",
    "run_all",
    "write_summaries",
]
