"""Load-history and road-profile file formats: pure readers and writers, no node code.

A *channel set* is what every reader returns and every writer takes: a time vector ``t``
[s] and named channels ``{name: values}`` of the same length, with their SI ``units``
(``{name: unit}``; "" when unknown). The formats:

:mod:`.mdf4` (ASAM MDF 4, float64, exact), :mod:`.rpc3` (MTS RPC III, one uniform time
step, 16-bit integers or 32-bit floats), :mod:`.tables` (CSV, Parquet). :func:`read_channels`
picks the reader from the file's suffix; a bad file is an InputFileError naming it.
"""

from __future__ import annotations

from .channel_set import FORMATS, SUFFIXES, ChannelSet, read_channels, write_channels
from .units import si_unit

__all__ = ["ChannelSet", "read_channels", "write_channels", "si_unit", "SUFFIXES", "FORMATS"]
