"""``suscosim scope RUN_OR_RUN_DIR``: watch a run live in the browser (docs/scope.md): a
local web server (port 8470): plots of the chosen channels, progress, node states, the damage
map; ``/data?since=K`` as JSON. A live run is watched like ``suscosim tap``; a finished one (or
``--replay``) is replayed from its journal. Plots by uPlot (MIT, vendored). Exit codes: 0
stopped, 1 the endpoint cannot be reached, 2 bad input.
"""

from __future__ import annotations

from .cli import build_parser, main

__all__ = ["build_parser", "main"]
