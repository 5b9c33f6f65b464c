"""The run journal: an append-only file of framed records that survives a crash.

Each record is one msgpack array ``[channel, payload, crc32]``: ``channel`` is
``"<node>/<channel>"``, ``payload`` the raw bus message exactly as received, ``crc32`` of the
channel's UTF-8 bytes followed by the payload (version 2; version 1, still read, covered the
payload only, so a flipped byte in a channel name went unnoticed). The first record is a
header ``["#suscosim-journal", VERSION, run_id]``.

Records are written as they arrive and flushed to the OS every ~50 ms, so a killed recorder
loses at most that much, and a killed node loses nothing the recorder had received. A torn
last record (the process died mid-write) is tolerated: the reader stops there and says so. A
damaged record in the middle (a flipped byte: bad CRC, or a frame that no longer parses) costs
that record only: the reader resynchronises on the next intact record and reports what it
skipped (:class:`Skipped`). Everything that reads a journal (``export``, ``runs``, ``sweep``'s
progress, ``report``, ``replay``) goes through :func:`read_journal`.
"""

from __future__ import annotations

import os
import struct
import zlib
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import msgpack

MAGIC = "#suscosim-journal"
VERSION = 2
VERSIONS = (1, 2)  # what the reader takes
HEADER_MAX = 64 * 1024  # the header record is read from the first bytes only


def record_crc(channel: str, payload: bytes, version: int = VERSION) -> int:
    """The CRC a record of a journal of ``version`` carries."""
    if version == 1:
        return zlib.crc32(payload)
    return zlib.crc32(payload, zlib.crc32(channel.encode()))


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
        self._buf.append(self._packer.pack([channel, payload, record_crc(channel, payload)]))
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
class Skipped:
    """A damaged stretch of a journal that the reader stepped over."""

    offset: int  # byte offset of its start
    length: int  # bytes
    records: int  # records in it, as far as their frames can still be told apart (>= 1)


@dataclass
class JournalContents:
    """What a journal holds: the run id, the good records, what was skipped, and whether the
    tail was torn. ``problem`` is one line for a user ("" when the journal is intact)."""

    run_id: str
    records: list[tuple[str, bytes]]
    torn: bool
    problem: str = ""
    skipped: list[Skipped] = field(default_factory=list)

    @property
    def skipped_records(self) -> int:
        return sum(s.records for s in self.skipped)

    @property
    def damaged(self) -> bool:
        """Records were lost in the middle of the journal (not just a torn tail)."""
        return bool(self.skipped)


class _Short(Exception):
    """The frame at this position runs past the end of the data (a torn tail)."""


_STR = {0xD9: (1, ">B"), 0xDA: (2, ">H"), 0xDB: (4, ">I")}
_BIN = {0xC4: (1, ">B"), 0xC5: (2, ">H"), 0xC6: (4, ">I")}
_UINT = {0xCC: (1, ">B"), 0xCD: (2, ">H"), 0xCE: (4, ">I")}


def _frame_at(data: bytes, pos: int) -> tuple[str, bytes, int, int] | None:
    """The frame ``[channel, payload, crc]`` starting at ``pos``, as the writer packs it:
    (channel, payload, crc, end), or None when ``pos`` does not start one. Raises _Short when
    a frame begins there but the data ends before it does. The CRC is not checked here."""
    n = len(data)
    if data[pos] != 0x93:
        return None
    i = pos + 1
    if i >= n:
        raise _Short
    b = data[i]
    if 0xA0 <= b <= 0xBF:
        ln, i = b & 0x1F, i + 1
    elif b in _STR:
        w, fmt = _STR[b]
        if i + 1 + w > n:
            raise _Short
        ln, i = struct.unpack_from(fmt, data, i + 1)[0], i + 1 + w
    else:
        return None
    if i + ln > n:
        raise _Short
    try:
        channel = data[i:i + ln].decode()
    except UnicodeDecodeError:
        return None
    i += ln
    if i >= n:
        raise _Short
    b = data[i]
    if b not in _BIN:
        return None
    w, fmt = _BIN[b]
    if i + 1 + w > n:
        raise _Short
    ln, i = struct.unpack_from(fmt, data, i + 1)[0], i + 1 + w
    if i + ln > n:
        raise _Short
    payload = data[i:i + ln]
    i += ln
    if i >= n:
        raise _Short
    b = data[i]
    if b <= 0x7F:
        return channel, payload, b, i + 1
    if b not in _UINT:
        return None
    w, fmt = _UINT[b]
    if i + 1 + w > n:
        raise _Short
    return channel, payload, struct.unpack_from(fmt, data, i + 1)[0], i + 1 + w


def _good_at(data: bytes, pos: int, version: int) -> tuple[str, bytes, int] | None:
    """(channel, payload, end) of an intact record (frame and CRC) at ``pos``, else None."""
    try:
        f = _frame_at(data, pos)
    except _Short:
        return None
    if f is None or record_crc(f[0], f[1], version) != f[2]:
        return None
    return f[0], f[1], f[3]


def _resync(data: bytes, start: int, version: int) -> int | None:
    """The first position at or after ``start`` holding an intact record, or None."""
    pos = data.find(b"\x93", start)
    while pos >= 0:
        if _good_at(data, pos, version) is not None:
            return pos
        pos = data.find(b"\x93", pos + 1)
    return None


def _frames_in(data: bytes, start: int, end: int) -> int:
    """How many frames (intact or not) a damaged stretch holds, as far as they can be told
    apart: at least 1."""
    count, pos = 0, start
    while pos < end:
        try:
            f = _frame_at(data, pos)
        except _Short:
            f = None
        if f is not None and f[3] <= end:
            count, pos = count + 1, f[3]
            continue
        nxt = data.find(b"\x93", pos + 1, end)
        if nxt < 0:
            break
        pos = nxt
    return max(1, count)


def iter_records(path: str | Path) -> Iterator[tuple[str, bytes]]:
    """The (channel, payload) records of a journal (damaged ones skipped, torn tail ignored)."""
    yield from read_journal(path).records


def _header(data: bytes, path: str | Path) -> tuple[str, int, int]:
    unpacker = msgpack.Unpacker(raw=False, use_list=True)
    unpacker.feed(data[:HEADER_MAX])
    try:
        header = next(unpacker)
    except (StopIteration, ValueError, msgpack.UnpackException) as exc:
        raise ValueError(f"{path}: not a suscosim journal (no header: {exc})") from None
    if not (isinstance(header, list) and len(header) == 3 and header[0] == MAGIC):
        raise ValueError(f"{path}: not a suscosim journal (bad header)")
    if header[1] not in VERSIONS:
        raise ValueError(f"{path}: journal version {header[1]} not supported "
                         f"(this reader takes {', '.join(map(str, VERSIONS))})")
    return str(header[2]), int(header[1]), unpacker.tell()


def read_journal(path: str | Path, tail_bytes: int | None = None) -> JournalContents:
    """Read a journal: every intact record, in order.

    Each record carries a CRC of its payload. A damaged record (bad CRC, or a frame that no
    longer parses: a flipped length or marker byte) is stepped over: the reader resynchronises
    on the next intact record and lists the stretch in ``skipped``. A torn last record (the
    writer died mid-write) ends the reading (``torn``). ``problem`` says both in one line.

    With ``tail_bytes``, only the header and the last ``tail_bytes`` of the file are read
    (cheap on a journal of any size: a live progress display); reading starts at the first
    intact record of that tail.
    """
    path = Path(path)
    base = 0  # file offset of data[0]
    if tail_bytes is None:
        data = path.read_bytes()
        run_id, version, pos = _header(data, path)
    else:
        with open(path, "rb") as fh:
            head = fh.read(HEADER_MAX)
            run_id, version, pos = _header(head, path)
            size = fh.seek(0, os.SEEK_END)
            start = base = max(pos, size - tail_bytes)
            fh.seek(start)
            data = fh.read()
        found = _resync(data, 0, version) if start > pos else 0
        pos = len(data) if found is None else found
    records: list[tuple[str, bytes]] = []
    skipped: list[Skipped] = []
    torn, problem = False, ""
    n = len(data)
    while pos < n:
        try:
            f = _frame_at(data, pos)
        except _Short:
            f, short = None, True
        else:
            short = False
        if f is not None and record_crc(f[0], f[1], version) == f[2]:
            records.append((f[0], f[1]))
            pos = f[3]
            continue
        nxt = _resync(data, pos + 1, version)
        if nxt is None:
            if f is not None:  # a complete frame with a bad CRC, nothing intact after it
                skipped.append(Skipped(base + pos, f[3] - pos, 1))
                pos = f[3]
                continue
            torn = True
            what = "torn" if short else "unreadable"
            problem = f"{what} record at byte {base + pos} ({n - pos} bytes)"
            break
        skipped.append(Skipped(base + pos, nxt - pos, _frames_in(data, pos, nxt)))
        pos = nxt
    if skipped:
        where = ", ".join(f"byte {s.offset} ({s.length} bytes)" for s in skipped[:5])
        more = f" and {len(skipped) - 5} more" if len(skipped) > 5 else ""
        text = (f"{sum(s.records for s in skipped)} damaged record(s) skipped at {where}{more}; "
                f"{len(records)} intact records kept")
        problem = text + (f"; {problem}" if problem else "")
    return JournalContents(run_id, records, torn, problem, skipped)


TAIL_BYTES = 64 * 1024
"""How much of a journal's end :func:`last_step` reads."""


def last_step(path: str | Path, tail_bytes: int = TAIL_BYTES) -> int | None:
    """The last step ``k`` every channel in the journal's tail has reached, or None (no
    journal, no data record in the tail). Only the header and the last ``tail_bytes`` are
    read, so it is cheap on a journal of any size (``runs``, a sweep's progress display)."""
    try:
        contents = read_journal(path, tail_bytes=tail_bytes)
    except (OSError, ValueError):
        return None
    last: dict[str, int] = {}
    for channel, raw in contents.records:
        try:
            obj = msgpack.unpackb(raw, raw=False)
        except Exception:  # a payload the bus would have rejected: not a step
            continue
        k = obj.get("k") if isinstance(obj, dict) and obj.get("kind") == "data" else None
        if isinstance(k, int):
            last[channel] = max(last.get(channel, -1), k)
    return min(last.values()) if last else None
