"""``suscosim scope RUN_OR_RUN_DIR``: watch a run live in the browser (docs/scope.md).

A local web server (loopback, port 8470 by default): time plots of the chosen channels, the
run's progress, each node's state and the live damage map; ``/data?since=K`` serves the same
as JSON. A running run is watched like ``suscosim tap`` (nothing published: the run does not
change); a finished one (or ``--replay``) is replayed from its journal at ``--speed``. Plots
by uPlot (MIT, vendored here). Exit codes: 0 stopped, 1 the run's endpoint cannot be reached
(client mode), 2 bad input (pattern, run, port in use, speed).

Modules: :mod:`.selection` (``--channels``), :mod:`.state` (the ``/data`` answer),
:mod:`.sources` (live bus, journal replay), :mod:`.damage`, :mod:`.server`, :mod:`.cli`.
"""

from __future__ import annotations

from .cli import build_parser, main

__all__ = ["build_parser", "main"]
