"""``python -m orchestrator.tap``: the same as ``suscosim tap``."""
from .cli import main

raise SystemExit(main())
