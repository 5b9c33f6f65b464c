"""``suscosim tap``: watch the messages of a running run (or of a replay), live.

A plain Zenoh subscriber on ``suscosim/<RUN>/<PATTERN>`` (no liveliness token, nothing sent:
the run neither waits for it nor sees it); its callback only queues the bytes, decoding and
display happen in the main thread. Arguments, display and ``--csv`` are in
docs/tap_replay.md. Undecodable messages are counted, never fatal. Exit codes: 0 done, 1 the
endpoint cannot be reached (client mode, after 10 s), 2 bad input.

Modules: :mod:`.target` (key expressions, the run folder's endpoints), :mod:`.fmt` (values as
text), :mod:`.csv_sink` (``--csv``), :mod:`.stats` (per-key counts and rates), :mod:`.cli`.
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
           "fmt_value", "is_loopback", "main", "resolve_target", "session_mode", "tap_keyexpr"]
