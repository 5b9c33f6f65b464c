"""The run journal: an append-only file of framed records that survives a crash.

Each record is one msgpack array ``[channel, payload, crc32]``: ``channel`` is
``"<node>/<channel>"``, ``payload`` the raw bus message exactly as received, ``crc32`` of the
payload. The first record is a header ``["#suscosim-journal", 1, run_id]``.

Records are written as they arrive and flushed to the OS every ~50 ms, so a killed recorder
loses at most that much, and a killed node loses nothing the recorder had received. A torn
last record (the process died mid-write) is tolerated: the reader stops there and says so.
"""

from __future__ import annotations

import os
import zlib
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import msgpack

MAGIC = "#suscosim-journal"
VERSION = 1


class JournalWriter:
    """Append records to ``path``; call :meth:`flush` often and :meth:`close` at the end."""

    def __init__(self, path: str | Path, run_id: str) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_APPEND, 0o644)
        self._buf: list[bytes] = []
        self._packer = msgpack.Packer(use_bin_type=True)
        self._buf.append(self._packer.pack([MAGIC, VERSION, run_id]))
        self.flush()
        self.records = 0

    def append(self, channel: str, payload: bytes) -> None:
        self._buf.append(self._packer.pack([channel, payload, zlib.crc32(payload)]))
        self.records += 1

    def flush(self) -> None:
        if self._buf:
            os.write(self._fd, b"".join(self._buf))
            self._buf.clear()

    def close(self) -> None:
        if self._fd >= 0:
            self.flush()
            os.fsync(self._fd)
            os.close(self._fd)
            self._fd = -1


@dataclass
class JournalContents:
    """What a journal holds: the run id, the records, and whether its tail was torn."""

    run_id: str
    records: list[tuple[str, bytes]]
    torn: bool
    problem: str = ""


def iter_records(path: str | Path) -> Iterator[tuple[str, bytes]]:
    """The (channel, payload) records of a journal; stops quietly at a torn tail."""
    yield from read_journal(path).records


def read_journal(path: str | Path) -> JournalContents:
    """Read a journal, tolerating a torn or corrupted tail (reported in ``problem``)."""
    data = Path(path).read_bytes()
    unpacker = msgpack.Unpacker(raw=False, use_list=True)
    unpacker.feed(data)
    records: list[tuple[str, bytes]] = []
    run_id, torn, problem = "", False, ""
    try:
        header = next(unpacker)
    except (StopIteration, ValueError, msgpack.UnpackException) as exc:
        raise ValueError(f"{path}: not a suscosim journal (no header: {exc})") from None
    if not (isinstance(header, list) and header[:1] == [MAGIC]):
        raise ValueError(f"{path}: not a suscosim journal (bad header)")
    if header[1] != VERSION:
        raise ValueError(f"{path}: journal version {header[1]} not supported (expected {VERSION})")
    run_id = str(header[2])
    while True:
        pos = unpacker.tell()
        try:
            rec = next(unpacker)
        except StopIteration:
            if pos < len(data):
                torn, problem = True, f"torn record at byte {pos} ({len(data) - pos} bytes)"
            break
        except Exception as exc:
            torn, problem = True, f"unreadable record at byte {pos}: {exc}"
            break
        ok = (isinstance(rec, list) and len(rec) == 3 and isinstance(rec[0], str)
              and isinstance(rec[1], bytes) and zlib.crc32(rec[1]) == rec[2])
        if not ok:
            torn, problem = True, f"corrupt record at byte {pos}"
            break
        records.append((rec[0], rec[1]))
    return JournalContents(run_id, records, torn, problem)
