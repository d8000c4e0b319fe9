"""Run pytest inside a Blender binary; the exit code of pytest becomes Blender's.

    blender -b --factory-startup --python-exit-code 1 \
        --python tests/blender/run_in_blender.py -- [pytest args]
"""

import os
import sys

import pytest

here = os.path.dirname(os.path.abspath(__file__))
args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
if not any(not a.startswith("-") for a in args):
    args.append(here)
code = int(pytest.main(["-p", "no:cacheprovider", *args]))
sys.stdout.flush()
sys.stderr.flush()
sys.exit(code)
