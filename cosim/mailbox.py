"""An input's mailbox: the decoded messages of one input channel a node has not used yet.

It files a verified message or rejects it with a reason, bounded whatever a producer sends: a
**stepped** input holds only the steps from the one last waited for up to
:data:`MAILBOX_WINDOW` ahead, any other input at most :data:`MAILBOX_MAX` messages. ``hello``
(step -1) is kept once; a second message for a filed step, a kind other than ``data`` or a
message lacking a needed field is rejected.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from . import keys
from .errors import WireError
from .wire import Message, codec, inner

MAILBOX_WINDOW = 64  # steps ahead of the one waited for that a stepped input accepts
MAILBOX_MAX = 256  # messages an input that is not stepped may hold


@dataclass
class Mailbox:
    """The messages of one input by step ``k`` (``-1``: the handshake's ``hello``)."""

    required: tuple[str, ...] = ()  # fields every data message must carry
    stepped: bool = True
    box: dict[int, Message] = field(default_factory=dict)
    floor: int = 0  # the step last taken: a stepped input accepts floor .. + MAILBOX_WINDOW

    def file(self, msg: Message) -> str | None:
        """File ``msg``; return why it is rejected instead (None: filed or kept)."""
        if msg.kind == "hello":
            self.box.setdefault(-1, msg)
            return None
        if msg.kind != "data":
            return f"unexpected kind '{msg.kind}' on a data channel"
        d = msg.d
        for name in self.required:
            if name not in d:
                missing = ", ".join(f for f in self.required if f not in d)
                return f"step {msg.k}: missing field(s) {missing}"
        if msg.k in self.box and msg.k >= 0:
            return f"duplicate message for step {msg.k}"
        if self.stepped:
            if not self.floor <= msg.k <= self.floor + MAILBOX_WINDOW:
                return f"step {msg.k} outside the window {self.floor}..." \
                       f"{self.floor + MAILBOX_WINDOW}"
        elif len(self.box) >= MAILBOX_MAX:
            return f"step {msg.k}: {MAILBOX_MAX} messages already wait"
        self.box[msg.k] = msg
        return None

    @property
    def heard(self) -> bool:  # a hello or data came: the producer's data path is live
        return bool(self.box)

    def take(self, k: int) -> Message:
        """The message of step ``k`` (it must be there); older steps are dropped."""
        msg = self.box[k]
        self.floor = k
        if len(self.box) > 1:
            for old in [j for j in self.box if j < k]:
                del self.box[old]
        return msg


def file_step(inputs: dict[tuple[str, str], Mailbox], node: str, msg: Message
              ) -> list[tuple[tuple[str, str], str]]:
    """File producer ``node``'s verified step message into ``inputs`` (a ``hello`` proves each
    stepped input from ``node`` live); the rejections, ``(input, why)``."""
    rejected: list[tuple[tuple[str, str], str]] = []
    if msg.kind == "hello":
        for (n, _), each in inputs.items():
            if n == node and each.stepped:
                each.file(msg)
        return rejected
    if msg.kind != "step":
        return [((node, keys.STEP), f"unexpected kind '{msg.kind}' on {node}/step")]
    for channel, raw in inner(msg):
        tag = (node, channel)
        box = inputs.get(tag)
        if box is None or not box.stepped:
            continue  # a channel this node does not read
        try:
            one = codec(f"{node}/{channel}").decode(raw)
        except WireError as exc:
            rejected.append((tag, str(exc)))
            continue
        why = box.file(one)
        if why is not None:
            rejected.append((tag, why))
    return rejected
