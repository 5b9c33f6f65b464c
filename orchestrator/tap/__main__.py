"""``python -m orchestrator.tap``: the same as ``suscosim tap``."""

import sys

from .cli import main

sys.exit(main())
