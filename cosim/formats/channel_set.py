"""The channel set every format reads and writes, and the reader/writer picked by suffix."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from cosim.errors import InputFileError
from cosim.safe_open import check_user_file

FORMATS = ("mdf4", "rpc3", "csv", "parquet")  # formats ``suscosim export --format`` writes
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


def read_channels(path: str | Path) -> ChannelSet:
    """Read any supported file (by suffix) into a checked :class:`ChannelSet`."""
    path = Path(path)
    fmt = format_of(path)
    check_user_file(path, "mdf" if fmt == "mdf4" else "loads", "load file")
    if fmt == "mdf4":
        from .mdf4 import read_mdf4 as reader
    elif fmt == "rpc3":
        from .rpc3 import read_rpc3 as reader
    elif fmt == "csv":
        from .tables import read_csv as reader
    else:
        from .tables import read_parquet as reader
    return reader(path).check(str(path))


def write_channels(cs: ChannelSet, path: str | Path, fmt: str, **options: Any
                   ) -> dict[str, Any]:
    """Write ``cs`` to ``path`` in ``fmt``; what the format reports (RPC III: resolution)."""
    writer: Callable[..., dict[str, Any]]
    if fmt == "mdf4":
        from .mdf4 import write_mdf4 as writer
    elif fmt == "rpc3":
        from .rpc3 import write_rpc3 as writer
    elif fmt == "csv":
        from .tables import write_csv as writer
    elif fmt == "parquet":
        from .tables import write_parquet as writer
    else:
        raise ValueError(f"unknown format {fmt!r}: expected one of {', '.join(FORMATS)}")
    return writer(cs, path, **options) or {}
