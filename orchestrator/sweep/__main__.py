"""``python -m orchestrator.sweep``: the same as ``suscosim sweep``."""

import sys

from .cli import main

sys.exit(main())
