"""Plain data on disk: how a checkpoint holds a node's state without holding code. A state is
encoded with msgpack: ``None``, ``bool``, ``int``, ``float``, ``str``, ``bytes``, ``list`` and
``dict`` as themselves, and as extension types a NumPy array or scalar
(dtype of :data:`NUMERIC_DTYPES` by name, shape, raw bytes in C order), a ``tuple``, ``set``,
``frozenset``, ``complex``, an ``int`` beyond 64 bits (decimal), a
``numpy.random.Generator`` (its bit generator's name and state), and an object of a class in
the whitelist :data:`CLASSES` (its name and fields: a dataclass's declared fields, another's
``__dict__`` or ``__slots__``). Decoding finds the class in the modules this process has
loaded (never imports what a file names) and sets the fields of a bare instance
(``object.__new__``) one by one: no method of the class runs, so the bytes can give wrong
numbers, never run code. Anything else is refused when encoding, and any malformed input when
decoding, with a :class:`PlainDataError` (never another exception).
"""

from __future__ import annotations

import dataclasses
import enum
import sys
from collections.abc import Callable
from typing import Any

import msgpack
import numpy as np

(_ARRAY, _SCALAR, _TUPLE, _SET, _FROZENSET, _COMPLEX, _OBJECT, _GENERATOR, _ENUM,
 _BIGINT) = range(1, 11)

NUMERIC_DTYPES = frozenset(
    np.dtype(f"{order}{kind}").str
    for kind in ("b1", "i1", "u1", "i2", "u2", "i4", "u4", "i8", "u8", "f2", "f4", "f8",
                 "c8", "c16")
    for order in ("<", ">"))
"""Booleans, integers, floats, complex, either byte order: never object, string, datetime."""

CLASSES = frozenset({
    "cosim.corner.Bush", "cosim.corner.Corner",
    "nodes.controller.mr_damper.MRDamper", "nodes.controller.mr_damper.MRParams",
    "nodes.controller.registry.LawSpec",
    "nodes.plant.anti_roll_bar.AntiRollBar", "nodes.plant.bump_stop.BumpStopParams",
    "nodes.plant.coupling.StepInputs", "nodes.plant.double_wishbone.DoubleWishboneParams",
    "nodes.plant.double_wishbone_geometry.CornerGeometry", "nodes.plant.driver.Driver",
    "nodes.plant.full_vehicle_7dof.FullVehicleParams",
    "nodes.plant.full_vehicle_dw.FullVehicleDWParams",
    "nodes.plant.quarter_car_lumped.LumpedQuarterCarParams",
    "nodes.tyre_road.magic_formula.MagicFormula", "nodes.tyre_road.tyre_3d.Tyre3D",
    "nodes.tyre_road.tyres.PointContact", "nodes.tyre_road.wheel_paths.RoadPath",
    "cosim.load_blocks.StepBlocks", "nodes.fatigue.config.FatigueConfig",
    "nodes.fatigue.lib.counting.StreamingRainflow", "nodes.fatigue.lib.fkm.FKMSpec",
    "nodes.fatigue.lib.influence_set.InfluenceSet", "nodes.fatigue.lib.life_models.SNCurve",
    "nodes.fatigue.lib.material.ComponentSpec", "nodes.fatigue.lib.material.Material",
    "nodes.fatigue.lib.screening.Screening",
    "nodes.fatigue.lib.screening.StressScreen", "nodes.fatigue.worker.LiveFatigue",
    "nodes.fatigue.worker._Engine", "nodes.fatigue.worker._Parked",
})
"""The classes (``module.QualName``) whose objects a node's state may hold."""
_BIT_GENERATORS = {"PCG64": np.random.PCG64, "PCG64DXSM": np.random.PCG64DXSM,
                   "MT19937": np.random.MT19937, "Philox": np.random.Philox,
                   "SFC64": np.random.SFC64}


class PlainDataError(ValueError):
    """A state that is not plain data (encoding), or bytes that do not decode to one."""


def class_name(cls: type) -> str:
    return f"{cls.__module__}.{cls.__qualname__}"


def _class(name: Any) -> type | None:
    """The whitelisted class ``name`` if its module is loaded in this process, else None."""
    if not isinstance(name, str) or name not in CLASSES:
        return None
    module, _, qual = name.rpartition(".")
    obj: Any = sys.modules.get(module)
    while module and obj is None and "." in module:  # a nested class: module.Outer.Inner
        module, _, outer = module.rpartition(".")
        qual = f"{outer}.{qual}"
        obj = sys.modules.get(module)
    for part in qual.split("."):
        obj = getattr(obj, part, None)
    return obj if isinstance(obj, type) and class_name(obj) == name else None


def _fields(obj: Any) -> dict[str, Any]:
    if dataclasses.is_dataclass(obj):
        out = {f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)}
        extra = getattr(obj, "__dict__", {})
        out.update({k: v for k, v in extra.items() if k not in out})
        return out
    if hasattr(obj, "__dict__"):
        return dict(vars(obj))
    slots = [s for c in type(obj).__mro__ for s in getattr(c, "__slots__", ())]
    return {s: getattr(obj, s) for s in slots if hasattr(obj, s)}


def _encoder(where: list[str]) -> Callable[[Any], Any]:
    def default(obj: Any) -> Any:
        if isinstance(obj, np.ndarray):
            if obj.dtype.str not in NUMERIC_DTYPES:
                raise PlainDataError(f"an array of dtype {obj.dtype} (not a number type)")
            return msgpack.ExtType(_ARRAY, _pack([obj.dtype.str, list(obj.shape),
                                                   np.ascontiguousarray(obj).tobytes()]))
        if isinstance(obj, np.generic):
            if obj.dtype.str not in NUMERIC_DTYPES:
                raise PlainDataError(f"a scalar of dtype {obj.dtype} (not a number type)")
            return msgpack.ExtType(_SCALAR, _pack([obj.dtype.str, obj.tobytes()]))
        if isinstance(obj, tuple) and type(obj) is tuple:
            return msgpack.ExtType(_TUPLE, _pack(list(obj), where))
        if type(obj) in (set, frozenset):
            code = _SET if type(obj) is set else _FROZENSET
            return msgpack.ExtType(code, _pack(sorted(obj, key=repr), where))
        if type(obj) is int:  # beyond 64 bits (a bit generator's state): decimal digits
            return msgpack.ExtType(_BIGINT, str(obj).encode())
        if type(obj) is complex:
            return msgpack.ExtType(_COMPLEX, _pack([obj.real, obj.imag]))
        if isinstance(obj, np.random.Generator):
            bg = obj.bit_generator
            return msgpack.ExtType(_GENERATOR, _pack([type(bg).__name__, bg.state]))
        name = class_name(type(obj))
        if name in CLASSES and _class(name) is type(obj):
            if isinstance(obj, enum.Enum):
                return msgpack.ExtType(_ENUM, _pack([name, obj.name]))
            return msgpack.ExtType(_OBJECT, _pack([name, _fields(obj)], where + [name]))
        raise PlainDataError(f"{'/'.join(where) or 'the state'}: a {name} is not plain data "
                             "(not in cosim.plaindata's whitelist)")
    return default


def _pack(obj: Any, where: list[str] | None = None) -> bytes:
    out: bytes = msgpack.packb(obj, default=_encoder(where or []), use_bin_type=True,
                               strict_types=True)
    return out


def encode(state: Any) -> bytes:
    """``state`` as plain-data bytes; :class:`PlainDataError` naming what is not plain data."""
    try:
        return _pack(state)
    except PlainDataError:
        raise
    except (TypeError, ValueError, OverflowError, RecursionError) as exc:
        raise PlainDataError(f"the state is not plain data: {exc}") from None


def _dtype(name: Any) -> np.dtype[Any]:
    if not isinstance(name, str) or name not in NUMERIC_DTYPES:
        raise PlainDataError(f"dtype {name!r} is not a number type")
    return np.dtype(name)


def _rebuild(name: Any, fields: Any, lenient: bool) -> Any:
    """An object of the whitelisted class ``name`` with ``fields``, no code of it run (with
    ``lenient``, a class not loaded here is a dict of its name and fields)."""
    cls = _class(name)
    if cls is None and lenient and name in CLASSES and isinstance(fields, dict):
        return {"class": name, "fields": fields}
    if cls is None:
        raise PlainDataError(f"class {name!r} is not in the whitelist of checkpoint classes")
    if not isinstance(fields, dict) or not all(
            isinstance(k, str) and k.isidentifier() and not k.startswith("__") for k in fields):
        raise PlainDataError(f"the fields of a {name} are not a dict of field names")
    if dataclasses.is_dataclass(cls):
        want = {f.name for f in dataclasses.fields(cls)}
        if not want <= set(fields):
            raise PlainDataError(f"a {name} lacks the fields {sorted(want - set(fields))}")
    obj: Any = object.__new__(cls)
    for key, value in fields.items():
        object.__setattr__(obj, key, value)
    return obj


def _ext(code: int, data: bytes, lenient: bool) -> Any:
    if code == _BIGINT:
        text = data.decode("ascii", "replace")
        if not 0 < len(text) <= 400 or not text.lstrip("-").isdigit():
            raise PlainDataError(f"a malformed integer {text[:40]!r}")
        return int(text)
    v = _unpack(data, lenient)
    if code == _ARRAY:
        if not (isinstance(v, list) and len(v) == 3 and isinstance(v[1], list)
                and all(isinstance(n, int) and n >= 0 for n in v[1]) and isinstance(v[2], bytes)):
            raise PlainDataError("a malformed array")
        dtype = _dtype(v[0])
        count = int(np.prod(v[1], dtype=np.int64)) if v[1] else 1
        if count * dtype.itemsize != len(v[2]):
            raise PlainDataError(f"an array of shape {v[1]} and {len(v[2])} bytes")
        return np.frombuffer(v[2], dtype=dtype).reshape(v[1]).copy()
    if code == _SCALAR:
        if not (isinstance(v, list) and len(v) == 2 and isinstance(v[1], bytes)):
            raise PlainDataError("a malformed scalar")
        dtype = _dtype(v[0])
        if len(v[1]) != dtype.itemsize:
            raise PlainDataError(f"a {dtype} scalar of {len(v[1])} bytes")
        return np.frombuffer(v[1], dtype=dtype)[0]
    if code in (_TUPLE, _SET, _FROZENSET) and isinstance(v, list):
        try:
            return (tuple, set, frozenset)[(_TUPLE, _SET, _FROZENSET).index(code)](v)
        except TypeError:
            raise PlainDataError("a set of unhashable items") from None
    if code == _COMPLEX and isinstance(v, list) and len(v) == 2 \
            and all(type(x) is float for x in v):
        return complex(v[0], v[1])
    if code == _OBJECT and isinstance(v, list) and len(v) == 2:
        return _rebuild(v[0], v[1], lenient)
    if code == _ENUM and isinstance(v, list) and len(v) == 2:
        cls = _class(v[0])
        if cls is None or not issubclass(cls, enum.Enum) or not isinstance(v[1], str) \
                or v[1] not in cls.__members__:
            raise PlainDataError(f"enum {v[0]!r}.{v[1]!r} is not in the whitelist")
        return cls.__members__[v[1]]
    if code == _GENERATOR and isinstance(v, list) and len(v) == 2:
        bg_cls = _BIT_GENERATORS.get(v[0]) if isinstance(v[0], str) else None
        if bg_cls is None or not isinstance(v[1], dict):
            raise PlainDataError(f"bit generator {v[0]!r} is not in the whitelist")
        bg = bg_cls()
        try:
            bg.state = v[1]
        except (TypeError, ValueError, KeyError, OverflowError) as exc:
            raise PlainDataError(f"a malformed {v[0]} state: {exc}") from None
        return np.random.Generator(bg)
    raise PlainDataError(f"a malformed value (extension type {code})")


def _unpack(data: bytes, lenient: bool) -> Any:
    return msgpack.unpackb(data, ext_hook=lambda c, d: _ext(c, d, lenient), raw=False,
                           strict_map_key=False, use_list=True)


def decode(data: bytes, lenient: bool = False) -> Any:
    """The state ``data`` holds; :class:`PlainDataError` for anything malformed. ``lenient``
    (a process without the node's modules): an object is ``{"class": name, "fields": {...}}``."""
    try:
        return _unpack(data, lenient)
    except PlainDataError:
        raise
    except (ValueError, TypeError, KeyError, OverflowError, RecursionError,
            msgpack.ExtraData, msgpack.FormatError, msgpack.StackError) as exc:
        raise PlainDataError(f"not plain data ({type(exc).__name__}: {exc})") from None
