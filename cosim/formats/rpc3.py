"""MTS RPC III time histories (``.rsp``, ``.tim``, ``.rpc``, ``.drv``) through ``rpc3-file``.

The rig's and nCode's format: a header of keyword/value pairs (``DESC.CHAN_n`` the channel
name, ``UNITS.CHAN_n`` its unit, ``DELTA_T`` the file's one time step), then demultiplexed data.

* ``SHORT_INTEGER`` (default, what rigs exchange): 16-bit counts, value = count x
  ``SCALE.CHAN_n`` with ``SCALE.CHAN_n = max|x| / 32752`` (rpc3-file's choice, the 16-count
  margin MTS keeps below 2^15): the **resolution** is one count, 3.05e-5 of the peak, a value
  read back within half a count. We write ``INT_FULL_SCALE = 32768``: readers that scale by
  ``SCALE.CHAN_n x INT_FULL_SCALE / 32768`` (``rpc-reader``) give the same numbers.
* ``FLOATING_POINT``: 32-bit IEEE floats (relative spacing 1.2e-7, rounding within 6e-8).

The table's ``t`` must be uniform (a run's is: t_k = k h); its first time is kept in the
header as ``SUSCOSIM_T0_S`` (RPC III starts at 0).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from cosim.errors import InputFileError

from .channel_set import ChannelSet

COUNTS = 32752  # largest count rpc3-file writes: a channel's resolution is max|x| / COUNTS
T0_KEY = "SUSCOSIM_T0_S"


def uniform_step(t: np.ndarray, what: str = "the table") -> float:
    """The time step of a uniform time axis [s]; ValueError when it is not uniform."""
    t = np.asarray(t, dtype=float)
    if t.size < 2:
        raise ValueError(f"{what} has fewer than 2 samples")
    dt = (t[-1] - t[0]) / (t.size - 1)
    if dt <= 0 or np.max(np.abs(np.diff(t) - dt)) > 1e-6 * dt:
        raise ValueError(f"{what} is not uniformly sampled (RPC III has one time step)")
    return float(dt)


def resolution(x: np.ndarray) -> float:
    """One count of a channel written as 16-bit integers [its unit]."""
    peak = float(np.max(np.abs(x))) if np.size(x) else 0.0
    return peak / COUNTS if peak > 0 else 1.0


def write_rpc3(cs: ChannelSet, path: str | Path, datatype: str = "int") -> dict[str, Any]:
    """Write ``cs`` as RPC III (``datatype`` "int": SHORT_INTEGER, "float": FLOATING_POINT);
    ``{"resolution": {name: ...}}``: one count (its unit), or float32's relative spacing."""
    import rpc3.rpc3 as lib

    if datatype not in ("int", "float"):
        raise ValueError(f"RPC III datatype must be 'int' or 'float', got {datatype!r}")
    path = Path(path)
    if path.suffix.lower() not in (".rsp", ".rpc"):
        raise ValueError(f"{path}: write RPC III as .rsp or .rpc")
    if not cs.channels:
        raise ValueError("no channel to write")
    dt = uniform_step(cs.t)
    lib.progressbar = False
    chans = [lib.Channel(name=name, unit=cs.units.get(name, ""), dt=dt,
                         data=np.asarray(x, dtype=np.float64))
             for name, x in cs.channels.items()]
    extra: dict[str, str | int] = {T0_KEY: repr(float(cs.t[0]))}
    if datatype == "int":
        extra["INT_FULL_SCALE"] = 32768
    lib.write(str(path), chans, datatype=int if datatype == "int" else float, overwrite=True,
              extra_params=extra)
    if datatype == "int":
        res = {n: resolution(x) for n, x in cs.channels.items()}
    else:
        res = {n: float(np.finfo(np.float32).eps) for n in cs.channels}
    return {"resolution": res, "datatype": datatype, "delta_t": dt}


def read_rpc3(path: str | Path) -> ChannelSet:
    """Every channel of an RPC III time history, in engineering units (count x SCALE)."""
    import rpc3.rpc3 as lib

    path = str(path)
    lib.progressbar = False
    try:
        channels, params = lib.read(path)
    except FileNotFoundError:
        raise InputFileError(path, "file not found") from None
    except Exception as exc:  # FileFormatError, struct/Unicode/ValueError on a foreign file
        raise InputFileError(path, f"not a readable RPC III file ({exc})") from None
    if not channels:
        raise InputFileError(path, "no channel in the file")
    if str(params.get("FILE_TYPE", "TIME_HISTORY")).upper() not in ("TIME_HISTORY",):
        raise InputFileError(path, f"FILE_TYPE {params.get('FILE_TYPE')!r}: a TIME_HISTORY "
                                   "is expected")
    n = min(ch.data.size for ch in channels)
    dt = float(channels[0].dt)
    try:
        t0 = float(params.get(T0_KEY, 0.0))
    except (TypeError, ValueError):
        t0 = 0.0
    integer = str(params.get("DATA_TYPE", "")).upper() == "SHORT_INTEGER"
    names: dict[str, np.ndarray] = {}
    units: dict[str, str] = {}
    res: dict[str, float] = {}
    for i, ch in enumerate(channels, start=1):
        name = str(ch.name).strip() or f"channel_{i}"
        if name in names:
            raise InputFileError(path, f"channel name {name!r} (DESC.CHAN_{i}) appears twice")
        x = np.asarray(ch.data[:n], dtype=np.float64)
        if integer:  # rpc3-file hands back float32: recover the exact counts, then x SCALE
            x = np.round(x / ch.resolution) * float(ch.resolution)
        names[name] = x
        units[name] = str(ch.unit or "").strip()
        res[name] = float(ch.resolution)
    t = t0 + dt * np.arange(n)
    return ChannelSet(t=t, channels=names, units=units,
                      meta={"resolution": res, "data_type": params.get("DATA_TYPE")})
