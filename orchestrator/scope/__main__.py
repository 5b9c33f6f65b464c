"""``python -m orchestrator.scope``: the same as ``suscosim scope``."""
from .cli import main

raise SystemExit(main())
