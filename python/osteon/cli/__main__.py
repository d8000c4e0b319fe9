"""``python -m osteon.cli``."""

import sys

from . import main

sys.exit(main())
