"""``suscosim tap``: watch the messages of a running run (or of a replay), live
(docs/tap_replay.md). A plain Zenoh subscriber on ``suscosim/<RUN>/<PATTERN>`` (nothing sent:
the run neither waits for it nor sees it); its callback only queues the bytes. Undecodable
messages are counted, never fatal. Exit codes: 0 done, 1 the endpoint cannot be reached
(client mode, after 10 s), 2 bad input.
"""

from __future__ import annotations

from cosim.zenoh_options import is_loopback, session_mode

from .cli import main
from .stats import CsvSink, Tap, fmt_value
from .target import DEFAULT_ENDPOINT, TapInputError, resolve_target, tap_keyexpr

__all__ = ["DEFAULT_ENDPOINT", "CsvSink", "Tap", "TapInputError", "fmt_value", "is_loopback",
           "main", "resolve_target", "session_mode", "tap_keyexpr"]
