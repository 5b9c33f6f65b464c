"""``suscosim scope``: watch a run live in the browser.

    suscosim scope RUN_OR_RUN_DIR [--channels PATTERN ...] [--port P] [--host H] [--open]
                   [--speed X | --fast] [--replay] [--duration S] [--buffer N]
                   [--connect EP ...] [--listen EP ...] [--lowlatency] [--mode auto|peer|client]
                   [--zenoh-config FILE]

A small local web server (loopback by default, port 8470) whose page shows, while the run
goes: time plots of the chosen channels (rolling window, autoscale, pause, SI units on the
axes), the run's progress and steps/s, each node's state (waiting, up, ready, stepping, done,
error, gone) and, when the live fatigue node runs, the lower arm's damage map and minimum
life, updated block by block. ``/data?since=K`` serves the same data as JSON to any tool.

* A **running** run (a run folder without ``summary.json``, or a run id with ``--connect``):
  the scope subscribes like ``suscosim tap`` -- no liveliness token, nothing published -- so
  the run neither waits for it nor changes (same table, bit for bit). Through a router
  (``--connect tcp/ROUTER:7447``) it watches a run on other machines (client session).
* A **finished** run (its folder has ``summary.json``; or ``--replay``): the journal is
  replayed into the page at ``--speed`` times the recorded pace (``--fast``: at once).

Plots are drawn by uPlot (MIT, vendored in this package: ``uPlot.iife.min.js``,
``uPlot.min.css``, ``uPlot.LICENSE``): no internet at run time.

The package: :mod:`.selection` (``--channels`` patterns, lines and units), :mod:`.state`
(what the page shows; the ``/data`` answer), :mod:`.sources` (live bus, journal replay),
:mod:`.damage` (the damage map), :mod:`.server` (HTTP), :mod:`.cli` (the command);
``scope.html``/``scope.js``/``scope.css`` (the page).

Exit codes: 0 stopped (Ctrl-C, SIGTERM, ``--duration``), 1 the run's endpoint cannot be
reached (client mode), 2 bad input (pattern, run, port in use, speed).
"""

from __future__ import annotations

from .cli import build_parser, main

__all__ = ["build_parser", "main"]
