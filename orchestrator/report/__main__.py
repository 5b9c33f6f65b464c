"""``python -m orchestrator.report``: the same as ``suscosim report``."""

import sys

from .cli import main

sys.exit(main())
