"""``python -m orchestrator.report``: the same as ``suscosim report``."""
from .cli import main

raise SystemExit(main())
