"""``python -m orchestrator.sweep``: the same as ``suscosim sweep``."""
from .cli import main

raise SystemExit(main())
