"""Reading a producer's ``step`` messages as the per-channel messages they carry.

A reader that thinks in channels (a tap, the scope) subscribes to the logical key expression
*and* its step key (:func:`step_keyexprs`) and expands each ``step`` message (:mod:`cosim.wire`)
into ``(suscosim/<run>/<node>/<channel>, message)`` pairs (:func:`expand`), keeping those the
logical expression matches (:func:`matches`: Zenoh's ``*`` and ``**``).
"""

from __future__ import annotations

from . import keys
from .bus import keyexpr_matches as matches
from .errors import WireError
from .wire import Message, decode, inner


def step_keyexprs(keyexpr: str) -> list[str]:
    """The key expressions to subscribe to for ``keyexpr``: itself, and the step key of the
    nodes it names (``suscosim/R/plant/state`` -> also ``suscosim/R/plant/step``)."""
    chunks = keyexpr.split("/")
    if chunks[-1] == "**" or len(chunks) < 2:
        return [keyexpr]  # already takes the step keys
    step = "/".join([*chunks[:-1], keys.STEP])
    return list(dict.fromkeys([keyexpr, step]))


def expand(key: str, msg: Message) -> list[tuple[str, Message]]:
    """``msg`` received on ``key``: a ``step`` as its inner messages (decoded, WireError if
    one is malformed), each on its channel's key; anything else as it is."""
    if msg.kind != "step":
        return [(key, msg)]
    run, node, _ = keys.parse_key(key)
    return [(keys.key(run, node, channel), decode(raw)) for channel, raw in inner(msg)]


def is_step_key(key: str) -> bool:
    """``key`` is a producer's step key (``.../<node>/step``)."""
    return key.rsplit("/", 1)[-1] == keys.STEP


__all__ = ["WireError", "expand", "is_step_key", "matches", "step_keyexprs"]
