import os
import sys
from pathlib import Path

import pytest
from hypothesis import settings

# CI runs the property tests on a fixed sequence of examples, so that a run cannot fail on a new
# random draw (locally they stay random and explore).
settings.register_profile("ci", derandomize=True)
if os.environ.get("CI"):
    settings.load_profile("ci")

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

# The test models live in the repository (tests/data, origins and licences in its SOURCES.md);
# OSTEON_DATA may point elsewhere (a folder with the same layout).
DATA = Path(os.environ.get("OSTEON_DATA", HERE.parent / "data"))


@pytest.fixture(scope="session")
def data_dir():
    if not DATA.is_dir():
        pytest.fail(f"test data not found at {DATA} (tests/data, or set OSTEON_DATA)")
    return DATA
