"""Journal versions 1 and 2 (read only; suscosim writes version 3, :mod:`cosim.journal`):
one msgpack array ``[channel, payload, crc32]`` per record after the header.

``crc32`` covers the channel's UTF-8 bytes followed by the payload (version 2; version 1
covered the payload only). A damaged record in the middle (bad CRC, or a frame that no longer
parses) costs that record: the reader resynchronises on the next intact record. How many
records a damaged stretch held can only be told as far as their frames can still be told
apart; where they cannot (e.g. 4 KiB of zeros), the count is estimated from the stretch's
length and the mean length of the intact records, and said to be an estimate.
"""

from __future__ import annotations

import struct
import zlib


def record_crc(channel: str, payload: bytes, version: int = 2) -> int:
    """The CRC a record of a journal of ``version`` (1 or 2) carries."""
    if version == 1:
        return zlib.crc32(payload)
    return zlib.crc32(payload, zlib.crc32(channel.encode()))


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


def resync(data: bytes, start: int, version: int) -> int | None:
    """The first position at or after ``start`` holding an intact record, or None."""
    pos = data.find(b"\x93", start)
    while pos >= 0:
        if _good_at(data, pos, version) is not None:
            return pos
        pos = data.find(b"\x93", pos + 1)
    return None


def frames_in(data: bytes, start: int, end: int) -> int:
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


def read_frames(data: bytes, pos: int, version: int, base: int
                ) -> tuple[list[tuple[str, bytes]], list[tuple[int, int, int, bool]], str]:
    """The intact records of ``data[pos:]`` (a version 1/2 journal's body; ``base`` is the file
    offset of ``data[0]``): (records, skipped stretches (offset, length, records, exact),
    problem of a torn or unreadable tail or "")."""
    records: list[tuple[str, bytes]] = []
    stretches: list[tuple[int, int, int]] = []
    problem = ""
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
        nxt = resync(data, pos + 1, version)
        if nxt is None:
            if f is not None:  # a complete frame with a bad CRC, nothing intact after it
                stretches.append((pos, f[3] - pos, 1))
                pos = f[3]
                continue
            what = "torn" if short else "unreadable"
            problem = f"{what} record at byte {base + pos} ({n - pos} bytes)"
            break
        stretches.append((pos, nxt - pos, frames_in(data, pos, nxt)))
        pos = nxt
    mean = (sum(len(c) + len(p) for c, p in records) / len(records) + 8) if records else 0.0
    skipped = []
    for start, length, counted in stretches:
        guess = round(length / mean) if mean else counted
        exact = counted >= guess
        skipped.append((base + start, length, counted if exact else guess, exact))
    return records, skipped, problem
