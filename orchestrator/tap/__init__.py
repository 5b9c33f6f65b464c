"""``suscosim tap``: watch the messages of a running run (or of a replay), live.

    suscosim tap [RUN] [PATTERN] [--connect EP ...] [--listen EP ...] [--csv FILE]
                 [--duration S] [--count N] [--raw] [--interval S] [--lowlatency]
                 [--mode auto|peer|client] [--zenoh-config FILE]

The tap is a plain Zenoh subscriber on ``suscosim/<RUN>/<PATTERN>``: it declares no
liveliness token and sends nothing, so the run neither waits for it nor sees it. Its callback
only queues the bytes (it never blocks Zenoh, so it never slows the run's publishers down);
decoding and display happen in the main thread.

* ``RUN``: a run id, ``*`` (every run: the default), or a run folder (then the run id and
  the endpoint come from its ``run.json``, written by ``suscosim run``).
* ``PATTERN`` (default ``**``): ``<node>/<channel>`` with ``*`` for any one name and ``**``
  for anything, e.g. ``plant/state``, ``*/force``, ``plant/*``; a single name is a node
  (``plant`` = ``plant/*``). A first argument with a ``/`` that is no folder is a pattern, so
  ``suscosim tap plant/state`` taps that channel of every run.
* Endpoint: ``--connect`` (repeatable); default the run folder's (its router if it has
  one, else the orchestrator's listen endpoint), else ``tcp/127.0.0.1:7447`` -- so a run
  started with ``--listen tcp/127.0.0.1:7447`` is tapped by a bare ``suscosim tap``.
  ``suscosim runs`` shows where each running run listens.
* Session mode (``--mode auto``): a Zenoh client (everything comes through the one
  orchestrator or router it connects to, on this machine as from another: a run's local
  nodes are an explicit mesh with gossip off that a peer would not join), opened as soon as
  the endpoint answers (a tap started before its run waits for it); a peer when it listens.

Display: per key, the message count and rate [msg/s], the last step ``k``, its time ``t``
[s] and the last values (arrays shortened), redrawn every ``--interval`` s (on a terminal;
otherwise printed as successive blocks). ``--raw`` prints every message as one line instead.
Messages that do not decode (foreign schema version, not msgpack) are counted and reported,
never fatal. ``--csv FILE`` appends one row per data message: ``key,k,t`` and the fields
(lists flattened to ``name[i]``); when a channel with new fields appears the file is
rewritten with the wider header (older rows get empty cells).

Stops on Ctrl-C, SIGTERM, after ``--duration`` s or after ``--count`` data messages, with a
final summary line ``tap: M messages (D data, C control), U undecodable on K key(s)``.
Exit codes: 0 done, 1 the endpoint cannot be reached (client mode, after 10 s), 2 bad input

The package: :mod:`.target` (key expressions, the run folder's endpoints), :mod:`.fmt` (values
as text and columns), :mod:`.csv_sink` (``--csv``), :mod:`.stats` (per-key counts, rates and
the table), :mod:`.cli` (the command). Session options: :mod:`cosim.zenoh_options`.
"""

from __future__ import annotations

from cosim.zenoh_options import apply_mode, is_loopback, session_mode

from .cli import build_parser, main
from .csv_sink import CsvSink
from .fmt import flatten, fmt_fields, fmt_value
from .stats import KeyStats, Tap
from .target import (
    DEFAULT_ENDPOINT,
    TapInputError,
    Target,
    channel_keyexpr,
    resolve_target,
    tap_keyexpr,
)

__all__ = ["DEFAULT_ENDPOINT", "CsvSink", "KeyStats", "Tap", "TapInputError", "Target",
           "apply_mode", "build_parser", "channel_keyexpr", "flatten", "fmt_fields",
           "fmt_value", "is_loopback", "main", "resolve_target", "session_mode",
           "tap_keyexpr"]
