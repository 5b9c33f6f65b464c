"""Load-history and road-profile file formats: pure readers and writers, no node code.

A *channel set* is what every reader returns and every writer takes: a time vector ``t``
[s] and named channels ``{name: values}`` of the same length, with their SI ``units``
(``{name: unit}``; "" when unknown). The formats:

* :mod:`.mdf4`  ASAM MDF 4 (``.mf4``) via ``asammdf``: float64, exact; names and units.
* :mod:`.rpc3`  MTS RPC III (``.rsp``/``.tim``/``.rpc``) via ``rpc3-file``: one uniform time
  step; 16-bit integers (resolution max|x| / 32752 per channel) or 32-bit floats.
* :mod:`.tables` CSV (header row; ``name [unit]`` headers understood) and Parquet (units in
  the field metadata).

:func:`read_channels` picks the reader from the file's suffix (:data:`SUFFIXES`).
Every problem with a file raises :class:`cosim.errors.InputFileError` naming the file.
"""

from __future__ import annotations

from .channel_set import FORMATS, SUFFIXES, ChannelSet, read_channels, write_channels
from .units import si_unit

__all__ = ["ChannelSet", "read_channels", "write_channels", "si_unit", "SUFFIXES", "FORMATS"]
