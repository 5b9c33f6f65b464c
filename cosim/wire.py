"""The wire format: every bus message is one msgpack map, versioned, SI units.

Schema (version 1)::

    {"v": 1,            # schema version (int); a node refuses versions it does not know
     "kind": "data",    # data | hello | ready | waiting | start | progress | done | abort
                        # | error | records | step
     "k": 42,           # communication step index (int, -1 before the run starts)
     "t": 0.042,        # time t_k of that step [s]
     "d": {...}}        # payload

For ``kind == "data"`` the payload maps field names (:mod:`cosim.schema`) to a number or a
list of numbers (one per corner; a quarter car sends plain numbers). Control kinds carry a
free msgpack map. ``records`` (``<node>/records``, the recorder's feed) and ``step``
(``<node>/step``: one producer's messages of one step as ONE bus message) carry other data
messages, each as it would be on its own (unsigned: the bundle's signature covers it),
``d = {FIELD: [[channel, raw message bytes], ...]}``, ``k``/``t`` the newest inner message's;
a consumer decodes only the inner messages of the channels it reads (:func:`inner`).

Encoding and decoding are msgspec's (compiled): with ``channel`` the numbers are bounded by
its limit (NaN, +-inf, 1e308 refused), its non-negative fields checked, ``k, t >= 0``; a
message that fails is explained field by field. A signed message has a sixth field ``"s"``.
"""

from __future__ import annotations

import functools
import math
import operator
from collections.abc import Mapping
from typing import Annotated, Any, NamedTuple, cast

import msgpack
import msgspec
import numpy as np

from . import schema
from .errors import WireError

SCHEMA_VERSION = 1
MAX_MESSAGE_BYTES = 48 * 1024
"""Largest message a node publishes [bytes]: Zenoh's low-latency transport does not fragment
(a message must fit one 64 KiB batch with its headers)."""
CONTROL_KINDS = ("hello", "ready", "waiting", "start", "progress", "done", "abort", "error",
                 "checkpoint")
KINDS = frozenset({"data", "records", "step", *CONTROL_KINDS})
BUNDLE_KINDS = ("records", "step")  # d[BUNDLE_FIELD[kind]] = [[channel, raw], ...]
BUNDLE_FIELD = {"records": "records", "step": "msgs"}


class Message(NamedTuple):
    """A decoded bus message (a named tuple: cheap, made for every message)."""

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


def _enc_hook(obj: Any) -> Any:
    """numpy values for the compiled encoder (called for the types it does not know): an
    array as floats, a length-1 one as a plain float."""
    if type(obj) is np.ndarray:
        if obj.dtype.kind != "f":
            obj = obj.astype(float)
        return obj.item() if obj.size == 1 else obj.ravel().tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    raise TypeError(f"can not serialize {type(obj).__name__!r} object")


_encoder = msgspec.msgpack.Encoder(enc_hook=_enc_hook)


def encode(kind: str, k: int, t: float, d: Mapping[str, Any] | None = None) -> bytes:
    """Encode one message. ``d`` values may be numpy arrays."""
    payload = d if type(d) is dict else dict(d or {})
    return _encoder.encode({"v": SCHEMA_VERSION, "kind": kind, "k": int(k), "t": float(t),
                            "d": payload})


# ---- the typed structs (decoded in C) -------------------------------------------------------
_Finite = Annotated[float, msgspec.Meta(ge=-1.7976931348623157e308, le=1.7976931348623157e308)]
_Step = Annotated[int, msgspec.Meta(ge=-1)]
_AnyNumber = int | float
_RawPayload = dict[str, _AnyNumber | Annotated[list[_AnyNumber], msgspec.Meta(min_length=1)]]


class _Envelope(msgspec.Struct, tag_field="kind"):
    v: int
    k: _Step
    t: _Finite


class _Records(_Envelope, tag="records"):
    d: dict[str, list[tuple[str, bytes]]]


class _StepBundle(_Envelope, tag="step"):
    d: dict[str, list[tuple[str, bytes]]]


_CONTROL = tuple(msgspec.defstruct(f"_C_{kind}", [("d", dict[str, Any])], bases=(_Envelope,),
                                   tag=kind) for kind in CONTROL_KINDS)


def _data_struct(name: str, payload: Any, k: Any, t: Any) -> Any:
    return msgspec.defstruct(name, [("k", k), ("t", t), ("d", payload)], bases=(_Envelope,),
                             tag="data")


_KIND_OF: dict[type, str] = {_Records: "records", _StepBundle: "step"}
_KIND_OF.update({c: kind for c, kind in zip(_CONTROL, CONTROL_KINDS, strict=True)})


def _decoder(data: Any) -> msgspec.msgpack.Decoder[Any]:
    _KIND_OF[data] = "data"
    union = functools.reduce(operator.or_, _CONTROL, data | _Records | _StepBundle)
    return msgspec.msgpack.Decoder(union)


_GENERIC = _decoder(_data_struct("_Data", _RawPayload, _Step, _Finite))
_NONNEG_T = Annotated[float, msgspec.Meta(ge=0.0, le=1.7976931348623157e308)]
_BY_LIMIT: dict[float, msgspec.msgpack.Decoder[Any]] = {}


def _channel_decoder(limit: float) -> msgspec.msgpack.Decoder[Any]:
    dec = _BY_LIMIT.get(limit)
    if dec is None:
        dec = _BY_LIMIT[limit] = _decoder(_data_struct(
            f"_Data_{len(_BY_LIMIT)}", schema.payload_type(limit),
            Annotated[int, msgspec.Meta(ge=0)], _NONNEG_T))
    return dec


class ChannelCodec:
    """The decoder of one channel (``node/channel``): bounds from :mod:`cosim.schema`."""

    def __init__(self, name: str) -> None:
        node, _, chan = name.partition("/")
        spec = schema.channel(node, chan)
        self.name = name
        self.limit = spec.limit if spec is not None else schema.DEFAULT_LIMIT
        self.nonneg = schema.nonneg_fields(node, chan)
        self.declared = tuple(f.name for f in spec.fields) if spec is not None else ()
        self.records = chan == "records"
        self.node = node
        self._dec = _channel_decoder(self.limit)

    def decode(self, raw: bytes) -> Message:
        try:
            m = self._dec.decode(raw)
        except (msgspec.DecodeError, msgspec.ValidationError):
            m = self._undeclared(raw)
        kind = _KIND_OF[type(m)]
        if m.v != SCHEMA_VERSION:
            raise WireError(_version(m.v))
        d = m.d
        if kind == "data" and self.limit == math.inf:  # unbounded: NaN is still refused
            bad = next((f for f in self.declared if f in d and _beyond(d[f], math.inf)), None)
            if bad is not None:
                raise WireError(f"{self.name} step {m.k}: field '{bad}'={d[bad]!r:.40} is "
                                "not a number (NaN)")
        if kind == "data" and self.nonneg:
            bad = schema.negative(d, self.nonneg)
            if bad is not None:
                raise WireError(f"{self.name} step {m.k}: field '{bad}'={d[bad]!r:.40} is "
                                "negative (the schema says >= 0)")
        return Message(kind, m.k, m.t, d)

    def _undeclared(self, raw: bytes) -> Any:
        """The slow path: ``raw`` failed the bounded decoder. It is taken if only undeclared
        fields are out of bounds (a law's extras may be NaN), else WireError saying why."""
        try:
            m = _GENERIC.decode(raw)
        except (msgspec.DecodeError, msgspec.ValidationError):
            m = None
        if m is None or _KIND_OF[type(m)] != "data" or m.k < 0 or m.t < 0 \
                or any(f in m.d and _beyond(m.d[f], self.limit) for f in self.declared):
            raise WireError(_explain(raw, self))
        return m


def _beyond(value: Any, limit: float) -> bool:
    """``value`` (a number or a list of them) is not within [-limit, limit] (NaN never is)."""
    return not all(-limit <= x <= limit for x in (value if type(value) is list else (value,)))


_CODECS: dict[str, ChannelCodec] = {}


def codec(name: str) -> ChannelCodec:
    """The (cached) codec of channel ``name`` (``node/channel``)."""
    c = _CODECS.get(name)
    if c is None:
        if len(_CODECS) > 256:  # a flood of made-up channel names cannot grow it
            return ChannelCodec(name)
        c = _CODECS[name] = ChannelCodec(name)
    return c


def inner(msg: Message) -> list[tuple[str, bytes]]:
    """The ``[channel, raw]`` pairs a ``records`` or ``step`` message carries (or WireError)."""
    try:
        return cast(list[tuple[str, bytes]], msg.d[BUNDLE_FIELD[msg.kind]])
    except KeyError:
        raise WireError(f"a {msg.kind} message without its messages") from None


def encode_step(k: int, t: float, msgs: list[tuple[str, bytes]]) -> bytes:
    """One producer's step (``kind == "step"``): its data messages ``[(channel, raw)]``."""
    return encode("step", k, t, {"msgs": msgs})


def decode(raw: bytes, channel: str | None = None) -> Message:
    """Decode and validate one message (WireError saying what is wrong); with ``channel``
    (``node/channel``) against that channel's schema, else the numbers only type-checked."""
    if channel is not None:
        return codec(channel).decode(raw)
    try:
        m = _GENERIC.decode(raw)
    except (msgspec.DecodeError, msgspec.ValidationError):
        raise WireError(_explain(raw, None)) from None
    if m.v != SCHEMA_VERSION:
        raise WireError(_version(m.v))
    return Message(_KIND_OF[type(m)], m.k, m.t, m.d)


# ---- the slow path: what is wrong, field by field (errors only) -----------------------------
_NUMBER_TYPES = (int, float)  # exact types (``type(x) in``): a bool is not a number here


def _version(version: Any) -> str:
    return f"unknown schema version {version!r} (this node speaks {SCHEMA_VERSION})"


def _explain(raw: bytes, chan: ChannelCodec | None) -> str:
    """Why ``raw`` does not decode, field by field."""
    try:
        obj = msgpack.unpackb(raw, raw=False, strict_map_key=True)
    except Exception as exc:  # msgpack raises several unrelated types
        return f"not msgpack ({type(exc).__name__}: {exc})"
    if not isinstance(obj, dict):
        return f"expected a map, got {type(obj).__name__}"
    version = obj.get("v")
    if version != SCHEMA_VERSION:
        return _version(version)
    kind, k, t, d = obj.get("kind"), obj.get("k"), obj.get("t"), obj.get("d")
    if kind not in KINDS:
        return f"unknown kind {kind!r}"
    if not isinstance(k, int) or isinstance(k, bool) or k < -1:
        return f"bad step index k={k!r} (expected int >= -1)"
    if type(t) not in _NUMBER_TYPES or not math.isfinite(cast(float, t)):
        return f"bad time t={t!r} (expected a finite number, s)"
    if not isinstance(d, dict) or not all(type(n) is str for n in d):
        return f"bad payload d of type {type(d).__name__} (expected a map of names)"
    if kind in BUNDLE_KINDS:
        return f"{kind} payload is not a list of [channel, bytes] pairs"
    if kind != "data":
        return f"bad {kind} message"
    where = f"{chan.name} " if chan is not None else ""
    for name, value in d.items():
        if type(value) in _NUMBER_TYPES:
            continue
        if not (type(value) is list and value
                and all(type(x) in _NUMBER_TYPES for x in value)):
            return f"data field '{name}'={value!r:.40} is not a number or list of numbers"
    if chan is None:
        return "malformed data message"
    if k < 0 or cast(float, t) < 0:
        return f"{where}data at step {k}, t={t!r}: a data message has k >= 0 and t >= 0 s"
    for name, value in d.items():
        if name not in chan.declared:
            continue
        for x in value if type(value) is list else (value,):
            if not -chan.limit <= x <= chan.limit:
                return (f"{where}step {k}: field '{name}'={x!r:.40} is implausible (not "
                        f"finite, or beyond +-{chan.limit:.0e}: cosim/schema.py)")
    return f"{where}malformed data message"
