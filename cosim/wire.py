"""The wire format: every bus message is one msgpack map, versioned, SI units.

Schema (version 1)::

    {"v": 1,            # schema version (int); a node refuses versions it does not know
     "kind": "data",    # data | hello | ready | waiting | start | progress | done | abort
                        # | error | records
     "k": 42,           # communication step index (int, -1 before the run starts)
     "t": 0.042,        # time t_k of that step [s]
     "d": {...}}        # payload

For ``kind == "data"`` the payload maps field names to a number or a list of numbers (one per
corner for per-corner quantities; a quarter car sends plain numbers). Field names and units of
each channel are listed in :mod:`cosim.channels`. Control kinds carry a free msgpack map.

``kind == "records"`` is the recorder's feed (``suscosim/<run>/<node>/records``): a node's
data messages of the last few steps, exactly as published, ``d = {"records": [[channel,
raw message bytes], ...]}`` in publication order; ``k``/``t`` are those of the last one.
The batch is signed; the messages in it are not (the batch's signature covers them).

Every message a run publishes is signed with the run's key: the map gets a sixth field, last,
``"s"``: 16 bytes, the MAC of the five before it (see :mod:`cosim.auth`). A reader without
the key (a tap, replay, a plain ``msgpack.unpackb``) reads the message as before and may
ignore ``s``; nodes and the orchestrator check it first with
:meth:`cosim.auth.RunKey.verify`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, NamedTuple, cast

import msgpack
import numpy as np

from .errors import WireError

SCHEMA_VERSION = 1
MAX_MESSAGE_BYTES = 48 * 1024
"""Largest message a node publishes [bytes]. Zenoh's low-latency transport (the embedded
default) does not fragment: a message must fit one 64 KiB batch with its headers, or it is
dropped. Data messages are far smaller; batches (records, load blocks) are cut to fit."""
KINDS = frozenset({"data", "hello", "ready", "waiting", "start", "progress", "done", "abort",
                   "error", "records"})


class Message(NamedTuple):
    """A decoded bus message (a named tuple: made for every message, so it must be cheap)."""

    kind: str
    k: int
    t: float
    d: dict[str, Any]

    def array(self, name: str) -> np.ndarray:
        """Field ``name`` as a float array (length 1 for a scalar)."""
        try:
            value = self.d[name]
        except KeyError:
            raise WireError(f"message k={self.k} has no field '{name}'") from None
        return np.array(value if type(value) is list else (value,), dtype=float)


def _plain(value: Any) -> Any:
    """numpy -> msgpack-able; a length-1 array becomes a plain float."""
    if type(value) is np.ndarray:
        if value.dtype.kind != "f":
            value = value.astype(float)
        return value.item() if value.size == 1 else value.ravel().tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


def encode(kind: str, k: int, t: float, d: Mapping[str, Any] | None = None) -> bytes:
    """Encode one message. ``d`` values may be numpy arrays."""
    payload = {name: _plain(v) for name, v in (d or {}).items()}
    raw: bytes = msgpack.packb(
        {"v": SCHEMA_VERSION, "kind": kind, "k": int(k), "t": float(t), "d": payload},
        use_bin_type=True,
    )
    return raw


_NUMBER_TYPES = (int, float)  # exact types (``type(x) in``): a bool is not a number here


def decode(raw: bytes) -> Message:
    """Decode and validate one message; raise :class:`WireError` saying what is wrong."""
    try:
        obj = msgpack.unpackb(raw, raw=False, strict_map_key=True)
    except Exception as exc:  # msgpack raises several unrelated types
        raise WireError(f"not msgpack ({type(exc).__name__}: {exc})") from None
    if not isinstance(obj, dict):
        raise WireError(f"expected a map, got {type(obj).__name__}")
    version = obj.get("v")
    if version != SCHEMA_VERSION:
        raise WireError(f"unknown schema version {version!r} (this node speaks {SCHEMA_VERSION})")
    kind, k, t, d = obj.get("kind"), obj.get("k"), obj.get("t"), obj.get("d")
    if kind not in KINDS:
        raise WireError(f"unknown kind {kind!r}")
    if not isinstance(k, int) or isinstance(k, bool) or k < -1:
        raise WireError(f"bad step index k={k!r} (expected int >= -1)")
    if type(t) not in _NUMBER_TYPES or not math.isfinite(cast(float, t)):
        raise WireError(f"bad time t={t!r} (expected a finite number, s)")
    if not isinstance(d, dict):
        raise WireError(f"bad payload d of type {type(d).__name__} (expected a map)")
    if kind == "data":
        for name, value in d.items():
            if type(value) in _NUMBER_TYPES:
                continue
            if not (type(value) is list and value
                    and all(type(x) in _NUMBER_TYPES for x in value)):
                raise WireError(f"data field '{name}'={value!r} is not a number or list of numbers")
    if kind == "records":
        recs = d.get("records")
        if not isinstance(recs, list) or not all(
                isinstance(r, list) and len(r) == 2 and isinstance(r[0], str)
                and isinstance(r[1], bytes) for r in recs):
            raise WireError("records payload is not a list of [channel, bytes] pairs")
    return Message(kind, k, float(cast(float, t)), d)

