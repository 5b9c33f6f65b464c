"""What a node sends: its output channels, its step message and its records batches.

Every data message is encoded once and checked against its channel's schema before it
leaves (a diverged model ends the run naming the field). A **per-step channel**'s message
joins the node's *step*, ONE signed message on ``<node>/step`` (:meth:`Outbox.send`; two if
it would not fit one); a **block channel** (``stepped=False``) goes out at once on its own key.
Every data message is also kept for the recorder, sent in batches on ``<node>/records``
(:class:`RecordBatch`) right after the step they fell due with, never between a step's last
input and its output. ``hold=True`` (the plant's response and loads of the step before)
puts a message in the *next* step message, ahead of that step's own.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from typing import Any

from . import keys, schema
from .errors import RunError, WireError
from .wire import MAX_MESSAGE_BYTES, ChannelCodec, codec, encode, encode_step

Publisher = Callable[[bytes], None]

_HEADROOM = 1024  # bytes a step or records message leaves free for its envelope
RECORD_BATCH = 64  # messages a records batch holds at most
RECORD_PERIOD_S = 0.05  # how old a batch may grow before it is sent [s]


class RecordBatch:
    """The messages (``channel``, raw bytes) kept since the last batch went out."""

    def __init__(self) -> None:
        self.items: list[tuple[str, bytes]] = []
        self.bytes = 0
        self.k, self.t = -1, 0.0  # the last kept message's step and time [s]
        self.since = time.monotonic()

    def fits(self, raw: bytes) -> bool:
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


class Outbox:
    """The sending side of one node; ``publisher(key)`` makes a signing publisher."""

    def __init__(self, publisher: Callable[[str], Publisher], run: str, node: str) -> None:
        self._publisher, self.run, self.node = publisher, run, node
        self._outputs: dict[str, Publisher | None] = {}  # None: in the step message
        self._codecs: dict[str, ChannelCodec] = {}
        self._step: list[tuple[str, bytes]] = []  # this step's data messages, not sent yet
        self._held: list[tuple[str, bytes]] = []  # for the next step message (``hold``)
        self._step_kt: tuple[int, float] = (-1, 0.0)  # the newest message's of the two
        self._step_bytes = 0  # of both lists
        self._records_due = False  # a batch to send after the step (:meth:`send`)
        self._step_pub: Publisher | None = None
        self._records = RecordBatch()
        self._records_pub: Publisher | None = None

    @property
    def outputs(self) -> list[str]:
        return list(self._outputs)

    def output(self, channel: str) -> None:
        """Declare an output channel."""
        self._outputs[channel] = self._channel_publisher(channel)
        self._codecs[channel] = codec(f"{self.node}/{channel}")
        if self._records_pub is None:
            self._records_pub = self._publisher(keys.key(self.run, self.node, keys.RECORDS))

    def _channel_publisher(self, channel: str) -> Publisher | None:
        """A block channel's own publisher, or None for a per-step channel."""
        spec = schema.channel(self.node, channel)
        if spec is not None and not spec.stepped:
            return self._publisher(keys.key(self.run, self.node, channel))
        if self._step_pub is None:
            self._step_pub = self._publisher(keys.key(self.run, self.node, keys.STEP))
        return None

    def rebind(self, publisher: Callable[[str], Publisher]) -> None:
        """New publishers (signing bound to the run instance's nonce) for every output."""
        self._publisher, self._step_pub = publisher, None
        for channel in list(self._outputs):
            self._outputs[channel] = self._channel_publisher(channel)
        if self._records_pub is not None:
            self._records_pub = self._publisher(keys.key(self.run, self.node, keys.RECORDS))

    def publish(self, channel: str, k: int, t: float, data: Mapping[str, Any],
                record: bool = True, hold: bool = False) -> None:
        """One data message, kept for the recorder unless ``record`` is false."""
        raw = encode("data", k, t, data)
        if len(raw) > MAX_MESSAGE_BYTES:
            raise RunError(f"{self.node}/{channel}: a message of {len(raw)} bytes at step {k} "
                           f"(at most {MAX_MESSAGE_BYTES}: split it)")
        try:  # what a consumer would reject is never sent: a diverged model ends here
            self._codecs[channel].decode(raw)
        except WireError as exc:
            raise RunError(f"{self.node} cannot publish {exc} (did the model diverge?)") \
                from None
        pub = self._outputs[channel]
        if pub is None:
            if (self._step or self._held) and \
                    self._step_bytes + len(raw) > MAX_MESSAGE_BYTES - _HEADROOM:
                self.send(held=True)  # one message must carry it: the step goes in two
            (self._held if hold else self._step).append((channel, raw))
            self._step_bytes += len(raw) + 8
            if k >= self._step_kt[0]:
                self._step_kt = (k, t)
        else:
            pub(raw)
        if record:
            if not self._records.fits(raw):
                self._send_records()  # the batch must fit one message too
            if self._records.add(channel, raw, k, t):
                if pub is None:  # after the step it goes with
                    self._records_due = True
                else:
                    self._send_records()

    def send(self, held: bool = False) -> None:
        """Publish this step's data messages as one ``step`` message, the held ones first
        (nothing if there are none of this step, unless ``held``); then a due records batch."""
        if (self._step or (held and self._held)) and self._step_pub is not None:
            msgs = self._held + self._step if self._held else self._step
            kt, self._step, self._held, self._step_bytes = self._step_kt, [], [], 0
            self._step_kt = (-1, 0.0)
            self._step_pub(encode_step(*kt, msgs))
        if self._records_due:
            self._records_due = False
            self._send_records()

    def _send_records(self) -> None:
        raw = self._records.take()
        if raw is not None and self._records_pub is not None:
            self._records_pub(raw)

    def flush(self) -> None:
        """Send this step, what is held for the next and the records batch."""
        self.send(held=True)
        self._send_records()

    def hello(self) -> None:
        """``hello`` on every output key and the records feed (a data path is live)."""
        raw = encode("hello", -1, 0.0, {})
        for pub in (*self._outputs.values(), self._step_pub, self._records_pub):
            if pub is not None:
                pub(raw)
