"""Build the add-on zips (the engine wheels + the add-on, per platform): the packaging rules live
in blender_addon/addon_build.py, beside the add-on they pack; this is the command a developer
and the wheels workflow run.

    python scripts/build_addon.py [--wheel W ...] [--wheel-dir DIR] [--python PY ...]
        [--out DIR] [--pygel3d download|DIR|none]
"""

import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                                "blender_addon"))

from addon_build import main

if __name__ == "__main__":
    sys.exit(main())
