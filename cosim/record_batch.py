"""The data messages a node has published, kept for the recorder and sent in batches.

Every data message a node publishes also goes to the recorder, as published (the bytes it
signed), on ``<node>/records``: at most :data:`RECORD_BATCH` messages or
:data:`RECORD_PERIOD_S` old a batch, never more than one message may carry (batches keep the
recorder off the per-step critical path).
"""

from __future__ import annotations

import time

from .wire import MAX_MESSAGE_BYTES, encode

RECORD_BATCH = 64
"""Messages a batch holds at most."""
RECORD_PERIOD_S = 0.05
"""How old a batch may grow before it is sent [s]."""
_HEADROOM = 1024
"""Bytes a batch leaves free of :data:`cosim.wire.MAX_MESSAGE_BYTES` for its envelope."""


class RecordBatch:
    """The messages kept since the last batch went out (``channel``, raw bytes)."""

    def __init__(self) -> None:
        self.items: list[tuple[str, bytes]] = []
        self.bytes = 0
        self.k, self.t = -1, 0.0  # the last kept message's step and time [s]
        self.since = time.monotonic()

    def fits(self, raw: bytes) -> bool:
        """Whether ``raw`` still fits this batch's one message."""
        return self.bytes + len(raw) <= MAX_MESSAGE_BYTES - _HEADROOM

    def add(self, channel: str, raw: bytes, k: int, t: float) -> bool:
        """Keep one message; True when the batch is due (full, or old enough)."""
        self.items.append((channel, raw))
        self.bytes += len(raw) + 8
        self.k, self.t = k, t
        return len(self.items) >= RECORD_BATCH or \
            time.monotonic() - self.since >= RECORD_PERIOD_S

    def take(self) -> bytes | None:
        """The batch as one ``records`` message (None if empty); a new batch starts."""
        self.since = time.monotonic()
        if not self.items:
            return None
        batch, self.items, self.bytes = self.items, [], 0
        return encode("records", self.k, self.t, {"records": batch})
