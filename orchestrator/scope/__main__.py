"""``python -m orchestrator.scope``: the same as ``suscosim scope``."""

import sys

from .cli import main

sys.exit(main())
