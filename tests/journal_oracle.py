"""A version-2 journal writer for the reader's tests (the product writes version 3 only,
:class:`cosim.journal.JournalWriter`; versions 1 and 2 are still read, :mod:`cosim.journal_v2`)."""

from __future__ import annotations

from pathlib import Path

import msgpack

from cosim.journal import MAGIC, JournalWriter
from cosim.journal_v2 import record_crc


class V2Writer:
    """The old format: the header, then one ``[channel, payload, crc32]`` frame per record."""

    def __init__(self, path: str | Path, run_id: str) -> None:
        self._f = open(path, "wb")  # noqa: SIM115 (closed by close)
        self._pk = msgpack.Packer(use_bin_type=True)
        self._f.write(self._pk.pack([MAGIC, 2, run_id]))
        self.records = 0

    def append(self, channel: str, payload: bytes) -> None:
        self._f.write(self._pk.pack([channel, payload, record_crc(channel, payload)]))
        self.records += 1

    def flush(self) -> None:
        self._f.flush()

    def close(self) -> None:
        self._f.close()


def journal_writer(path: str | Path, run_id: str, version: int = 3) -> JournalWriter | V2Writer:
    """A writer of ``version`` 2 (this oracle) or 3 (the product's)."""
    return V2Writer(path, run_id) if version == 2 else JournalWriter(path, run_id)
