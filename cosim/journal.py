"""The run journal: an append-only file of compressed, checksummed segments that survives a
crash, read in bounded memory whatever its length.

The file starts with one msgpack record, the header ``["#suscosim-journal", VERSION, run_id]``.
Then segments follow, one per flush of the writer (every ~50 ms, or when the records held
reach :data:`SEGMENT_RAW_BYTES`)::

    "SJS3" | clen u32 | rawlen u32 | nrec u32 | first u64 | hcrc u32 | body (clen) | bcrc u32

(little-endian; docs/data_formats.md). ``body`` is one zstd frame of ``nrec`` msgpack arrays
``[channel, payload]`` (``"<node>/<channel>"``, the bus message as received); ``first``: the
records before this segment; ``hcrc``, ``bcrc``: CRC-32 of the 24 header bytes and of the body.

A segment is one ``write``, so a killed recorder loses at most its last ~50 ms (a torn last
segment, said so). A damaged segment costs that segment only: the reader resynchronises on
the next intact header and reports the records lost (:class:`Skipped`), from the ``first``
of the segments around it. Versions 1 and 2 (before 2026-12-02) are refused (exit 2).
"""

from __future__ import annotations

import os
import struct
import zlib
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

import msgpack

from .errors import InputFileError

MAGIC = "#suscosim-journal"
VERSION = 3
HEADER_MAX = 64 * 1024  # the header record is read from the first bytes only
SEG_MAGIC = b"SJS3"
_SEG = struct.Struct("<4sIIIQ")  # magic, clen, rawlen, nrec, first
SEG_HEAD = _SEG.size + 4  # + hcrc
SEGMENT_RAW_BYTES = 1 << 20  # a segment is cut when its records reach this (uncompressed)
MAX_SEGMENT_BYTES = 64 << 20  # a header claiming more is not taken for one
ZSTD_LEVEL = 3
_CHUNK = 1 << 20  # bytes read at a time


class JournalWriter:
    """Append records to ``path``; call :meth:`flush` often and :meth:`close` at the end."""

    def __init__(self, path: str | Path, run_id: str) -> None:
        import zstandard

        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_APPEND, 0o644)
        self._packer = msgpack.Packer(use_bin_type=True)
        os.write(self._fd, self._packer.pack([MAGIC, VERSION, run_id]))
        self._zstd = zstandard.ZstdCompressor(level=ZSTD_LEVEL, write_checksum=True)
        self._buf: list[bytes] = []
        self._buf_bytes = 0
        self._first = 0
        self.records = 0

    def append(self, channel: str, payload: bytes) -> None:
        self.records += 1
        rec = self._packer.pack([channel, payload])
        self._buf.append(rec)
        self._buf_bytes += len(rec)
        if self._buf_bytes >= SEGMENT_RAW_BYTES:
            self.flush()

    def flush(self) -> None:
        """Write what was appended since the last flush as one segment (one ``write``)."""
        if not self._buf:
            return
        raw = b"".join(self._buf)
        body = self._zstd.compress(raw)
        head = _SEG.pack(SEG_MAGIC, len(body), len(raw), len(self._buf), self._first)
        os.write(self._fd, b"".join((head, struct.pack("<I", zlib.crc32(head)), body,
                                     struct.pack("<I", zlib.crc32(body)))))
        self._first += len(self._buf)
        self._buf.clear()
        self._buf_bytes = 0

    def sync(self) -> None:
        """Flush, then fsync: what was appended is on the disk (a checkpoint's boundary)."""
        self.flush()
        os.fsync(self._fd)

    def close(self) -> None:
        if self._fd >= 0:
            self.flush()
            os.fsync(self._fd)
            os.close(self._fd)
            self._fd = -1


@dataclass
class Skipped:
    """A damaged stretch the reader stepped over: byte offset, length [bytes], records lost."""

    offset: int
    length: int
    records: int


@dataclass
class JournalContents:
    """What a journal holds: run id, good records (empty if streamed; ``count`` intact),
    what was skipped, whether the tail was torn (``torn_records`` lost, when known);
    ``problem``: one line for a user ("" when intact)."""

    run_id: str
    records: list[tuple[str, bytes]]
    torn: bool
    problem: str = ""
    skipped: list[Skipped] = field(default_factory=list)
    count: int = 0
    torn_records: int | None = None

    @property
    def skipped_records(self) -> int:
        return sum(s.records for s in self.skipped)

    @property
    def damaged(self) -> bool:  # records lost in the middle, not just a torn tail
        return bool(self.skipped)


def _header(data: bytes, path: str | Path) -> tuple[str, int]:
    unpacker = msgpack.Unpacker(raw=False, use_list=True)
    unpacker.feed(data[:HEADER_MAX])
    try:
        header = next(unpacker)
    except (StopIteration, ValueError, msgpack.UnpackException) as exc:
        raise InputFileError(str(path), f"not a suscosim journal (no header: {exc})") from None
    if not (isinstance(header, list) and len(header) == 3 and header[0] == MAGIC):
        raise InputFileError(str(path), "not a suscosim journal (bad header)")
    if header[1] != VERSION:
        raise InputFileError(str(path), f"journal version {header[1]!r:.20} not supported "
                             f"(this reader takes {VERSION})")
    return str(header[2]), unpacker.tell()


class _Window:
    """A sliding window over a file: bytes from absolute offset :attr:`base` on."""

    def __init__(self, fh: IO[bytes], base: int) -> None:
        self.fh, self.base, self.data = fh, base, b""
        fh.seek(base)
        self.eof = False

    def need(self, pos: int, n: int) -> bool:
        """Make ``[pos, pos + n)`` available (forgetting what is before ``pos``)."""
        if pos > self.base:
            self.data, self.base = self.data[pos - self.base:], pos
        while len(self.data) < pos - self.base + n and not self.eof:
            more = self.fh.read(max(_CHUNK, pos - self.base + n - len(self.data)))
            self.eof = not more
            self.data += more
        return len(self.data) >= pos - self.base + n

    def get(self, pos: int, n: int) -> bytes:
        return self.data[pos - self.base:pos - self.base + n]

    def end(self) -> int:
        """The offset of the end of the file (reads the rest: only for a tail)."""
        self.need(self.base, 1 << 62)
        return self.base + len(self.data)

    def find(self, pos: int) -> int:
        """The offset of the next segment magic at or after ``pos``, or -1."""
        while True:
            self.need(pos, len(SEG_MAGIC))
            i = self.data.find(SEG_MAGIC, pos - self.base)
            if i >= 0:
                return self.base + i
            if self.eof:
                return -1
            pos = self.base + max(0, len(self.data) - len(SEG_MAGIC) + 1)
            self.need(pos, len(self.data) - (pos - self.base) + _CHUNK)


def _head_at(win: _Window, pos: int) -> tuple[int, int, int, int] | None:
    """(clen, rawlen, nrec, first) of an intact segment header at ``pos``, else None."""
    if not win.need(pos, SEG_HEAD):
        return None
    raw = win.get(pos, SEG_HEAD)
    magic, clen, rawlen, nrec, first = _SEG.unpack_from(raw)
    if magic != SEG_MAGIC or struct.unpack_from("<I", raw, _SEG.size)[0] != zlib.crc32(
            raw[:_SEG.size]) or clen > MAX_SEGMENT_BYTES:
        return None
    return clen, rawlen, nrec, first


def _next_head(win: _Window, pos: int) -> int:
    """The offset of the next intact segment header after ``pos``, or -1."""
    while (pos := win.find(pos + 1)) >= 0:
        if _head_at(win, pos) is not None:
            return pos
    return -1


def _body_records(body: bytes, rawlen: int, nrec: int, dctx: Any) -> list[tuple[str, bytes]]:
    """The records of a segment body whose CRC matched; ValueError if it does not decode.
    Read by a stream that stops one byte past ``rawlen`` (zstd's ``decompress`` would inflate
    whatever size a forged frame states)."""
    if rawlen > MAX_SEGMENT_BYTES:
        raise ValueError(f"declares {rawlen} raw bytes, more than {MAX_SEGMENT_BYTES}")
    parts: list[bytes] = []
    got = 0
    try:
        with dctx.stream_reader(body) as reader:
            while got <= rawlen and (chunk := reader.read(min(rawlen + 1 - got, _CHUNK))):
                parts.append(chunk)
                got += len(chunk)
    except Exception as exc:  # zstandard.ZstdError
        raise ValueError(f"does not decompress: {exc}") from None
    if got != rawlen:
        raise ValueError(f"decompresses to {'more than ' if got > rawlen else ''}{got} bytes, "
                         f"the header says {rawlen}")
    raw = b"".join(parts)
    out: list[tuple[str, bytes]] = []
    try:
        u = msgpack.Unpacker(raw=False, max_buffer_size=max(len(raw), 1))
        u.feed(raw)
        for channel, payload in u:
            if type(channel) is not str or type(payload) is not bytes:
                raise TypeError("a record is not [channel, payload]")
            out.append((channel, payload))
    except (ValueError, TypeError, msgpack.UnpackException) as exc:
        raise ValueError(f"bad records: {exc}") from None
    if len(out) != nrec:
        raise ValueError(f"{len(out)} records where the header says {nrec}")
    return out


class JournalReader:
    """Stream a journal's intact records in bounded memory; then :meth:`contents` says what
    was skipped or torn. ``tail_bytes``: from the first whole segment of the file's last
    ``tail_bytes`` (doubled until there is one); ``decode=False``: CRCs checked, nothing yielded."""

    def __init__(self, path: str | Path, tail_bytes: int | None = None,
                 decode: bool = True) -> None:
        self.path = Path(path)
        with open(self.path, "rb") as fh:
            head = fh.read(HEADER_MAX)
        self.run_id, self._start = _header(head, self.path)
        self.tail_bytes, self.decode = tail_bytes, decode
        self._result: JournalContents | None = None

    def contents(self) -> JournalContents:
        """What the iteration (run to its end) found."""
        if self._result is None:
            raise RuntimeError("JournalReader.contents() before the records were read")
        return self._result

    def __iter__(self) -> Iterator[tuple[str, bytes]]:
        import zstandard

        dctx = zstandard.ZstdDecompressor()
        with open(self.path, "rb") as fh:
            pos = self._start
            expect: int | None = 0
            if self.tail_bytes is not None:
                pos, expect = self._tail_start(fh)
            win = _Window(fh, pos)
            skipped: list[Skipped] = []
            bad: list[tuple[int, int, int | None]] = []  # since the last good segment
            count, tail, torn_records = 0, "", None
            while True:
                if not win.need(pos, 1):
                    break
                head = _head_at(win, pos)
                if head is None:
                    nxt = _next_head(win, pos)
                    if nxt < 0:
                        length = win.end() - pos
                        what = "torn" if length < SEG_HEAD else "unreadable"
                        tail = f"{what} segment at byte {pos} ({length} bytes)"
                        torn_records = sum(n or 0 for _, _, n in bad) if bad else None
                        break
                    bad.append((pos, nxt - pos, None))
                    pos = nxt
                    continue
                clen, rawlen, nrec, first = head
                end = pos + SEG_HEAD + clen + 4
                if not win.need(pos, end - pos):
                    length = win.end() - pos
                    tail = (f"torn segment at byte {pos} ({length} of {end - pos} bytes, "
                            f"{nrec} records)")
                    torn_records = nrec
                    break
                body = win.get(pos + SEG_HEAD, clen)
                ok = struct.unpack_from("<I", win.get(end - 4, 4))[0] == zlib.crc32(body)
                recs: list[tuple[str, bytes]] = []
                if ok and self.decode:
                    try:
                        recs = _body_records(body, rawlen, nrec, dctx)
                    except ValueError:
                        ok = False
                if not ok:
                    bad.append((pos, end - pos, nrec))
                    pos = end
                    continue
                if expect is None:
                    expect = first
                skipped += _lost(bad, first - expect, pos)
                bad = []
                expect = first + nrec
                count += nrec
                pos = end
                yield from recs
            if bad and not tail:  # damaged segments at the very end, nothing intact after
                skipped += _lost(bad, sum(n or 0 for _, _, n in bad), pos)
        self._finish(skipped, count, tail, torn_records)

    def _tail_start(self, fh: IO[bytes]) -> tuple[int, int | None]:
        """Where the last ``tail_bytes`` (or more) hold a whole intact segment."""
        size = fh.seek(0, os.SEEK_END)
        want = int(self.tail_bytes or 0)
        while True:
            start = max(self._start, size - want)
            if start == self._start:
                return start, 0
            win = _Window(fh, start)
            pos = start - 1
            while (pos := _next_head(win, pos)) >= 0:
                head = _head_at(win, pos)
                assert head is not None
                if pos + SEG_HEAD + head[0] + 4 <= size:
                    return pos, None
            want *= 2

    def _finish(self, skipped: list[Skipped], count: int, tail: str,
                torn_records: int | None) -> None:
        problem = tail
        if skipped:
            where = ", ".join(f"byte {s.offset} ({s.length} bytes)" for s in skipped[:5])
            more = f" and {len(skipped) - 5} more" if len(skipped) > 5 else ""
            n = sum(s.records for s in skipped)
            text = (f"{n} damaged record(s) skipped at {where}{more}; "
                    f"{count} intact records kept")
            problem = text + (f"; {problem}" if problem else "")
        self._result = JournalContents(self.run_id, [], bool(tail), problem, skipped, count,
                                       torn_records)


def _lost(bad: list[tuple[int, int, int | None]], lost: int, pos: int) -> list[Skipped]:
    """The damaged stretches since the last good segment, with the ``lost`` records the
    segment numbers say they held: those whose header survived hold theirs, the first
    headless one the remainder."""
    if lost <= 0 and not bad:
        return []
    if not bad:  # records missing with no damage seen (bytes cut out)
        return [Skipped(pos, 0, lost)]
    known = sum(n for _, _, n in bad if n is not None)
    unknown = [i for i, (_, _, n) in enumerate(bad) if n is None]
    rest = max(0, lost - known)
    out = []
    for i, (off, length, n) in enumerate(bad):
        if n is None:
            n = rest if i == unknown[0] else 0
        out.append(Skipped(off, length, n))
    return out


def read_journal(path: str | Path, tail_bytes: int | None = None) -> JournalContents:
    """Every intact record of a journal, in order, in a list (:class:`JournalReader`)."""
    reader = JournalReader(path, tail_bytes)
    records = list(reader)
    contents = reader.contents()
    contents.records = records
    return contents


def iter_records(path: str | Path) -> Iterator[tuple[str, bytes]]:
    yield from JournalReader(path)


def scan_journal(path: str | Path) -> JournalContents:
    """The journal's integrity without its records (CRCs checked, nothing decompressed)."""
    reader = JournalReader(path, decode=False)
    for _ in reader:
        pass
    return reader.contents()


def segment_index(path: str | Path) -> list[tuple[int, int, int, int]]:
    """The intact segment headers of a journal: (offset, bytes, records, first record's index)."""
    reader = JournalReader(path)
    out = []
    with open(reader.path, "rb") as fh:
        win, pos = _Window(fh, reader._start), reader._start
        while (head := _head_at(win, pos)) is not None or (pos := _next_head(win, pos)) >= 0:
            if head is None:
                continue
            out.append((pos, SEG_HEAD + head[0] + 4, head[2], head[3]))
            pos += SEG_HEAD + head[0] + 4
    return out


TAIL_BYTES = 64 * 1024  # how much of a journal's end last_step reads (at least)


def last_step(path: str | Path, tail_bytes: int = TAIL_BYTES) -> int | None:
    """The last step every channel in the journal's tail has reached, or None."""
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
