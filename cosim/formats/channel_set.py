"""The channel set every format reads and writes, and the reader/writer picked by suffix."""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from cosim.errors import InputFileError
from cosim.safe_open import check_user_file

FORMATS = ("mdf4", "rpc3", "csv", "parquet")
"""Formats ``suscosim export --format`` writes."""
SUFFIXES = {".mf4": "mdf4", ".mdf": "mdf4", ".rsp": "rpc3", ".tim": "rpc3", ".rpc": "rpc3",
            ".drv": "rpc3", ".csv": "csv", ".parquet": "parquet"}
"""File suffix -> format, for reading."""
EXTENSION = {"mdf4": ".mf4", "rpc3": ".rsp", "csv": ".csv", "parquet": ".parquet"}
"""Format -> the suffix we write."""


@dataclass
class ChannelSet:
    """Time ``t`` [s] (strictly increasing) and named channels of the same length, their
    ``units`` ("" unknown) and ``meta`` the format adds (``meta["resolution"][name]``: RPC III)."""

    t: np.ndarray
    channels: dict[str, np.ndarray]
    units: dict[str, str] = field(default_factory=dict)
    meta: dict[str, Any] = field(default_factory=dict)

    def check(self, path: str) -> ChannelSet:
        """Raise InputFileError (naming ``path``) unless the set is usable as a history."""
        t = np.asarray(self.t, dtype=float)
        if t.ndim != 1 or t.size < 2:
            raise InputFileError(path, f"fewer than 2 samples ({t.size})")
        if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
            raise InputFileError(path, "the time axis is not strictly increasing")
        for name, x in self.channels.items():
            if x.shape != t.shape:
                raise InputFileError(path, f"channel {name!r} has {x.size} samples, the time "
                                           f"axis {t.size}")
            if not np.all(np.isfinite(x)):
                raise InputFileError(path, f"channel {name!r} has non-finite values")
        self.t = t
        return self


def format_of(path: str | Path) -> str:
    suffix = Path(path).suffix.lower()
    if suffix not in SUFFIXES:
        raise InputFileError(str(path), f"unknown load file type {suffix!r}: expected one of "
                                        + ", ".join(sorted(SUFFIXES)))
    return SUFFIXES[suffix]


_READERS = {"mdf4": (".mdf4", "read_mdf4"), "rpc3": (".rpc3", "read_rpc3"),
            "csv": (".tables", "read_csv"), "parquet": (".tables", "read_parquet")}
_WRITERS = {"mdf4": (".mdf4", "write_mdf4"), "rpc3": (".rpc3", "write_rpc3"),
            "csv": (".tables", "write_csv"), "parquet": (".tables", "write_parquet")}


def _function(table: dict[str, tuple[str, str]], fmt: str) -> Callable[..., Any]:
    """The reader or writer of ``fmt``, its module imported when first used."""
    module, name = table[fmt]
    fn: Callable[..., Any] = getattr(importlib.import_module(module, __package__), name)
    return fn


def read_channels(path: str | Path) -> ChannelSet:
    """Read any supported file (by suffix) into a checked :class:`ChannelSet`."""
    path = Path(path)
    fmt = format_of(path)
    check_user_file(path, "mdf" if fmt == "mdf4" else "loads", "load file")
    cs: ChannelSet = _function(_READERS, fmt)(path)
    return cs.check(str(path))


def write_channels(cs: ChannelSet, path: str | Path, fmt: str, **options: Any
                   ) -> dict[str, Any]:
    """Write ``cs`` to ``path`` in ``fmt``; what the format reports (RPC III: resolution)."""
    if fmt not in _WRITERS:
        raise ValueError(f"unknown format {fmt!r}: expected one of {', '.join(FORMATS)}")
    out: dict[str, Any] = _function(_WRITERS, fmt)(cs, path, **options) or {}
    return out
