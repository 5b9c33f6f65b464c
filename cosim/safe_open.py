"""Opening a file a user names (every reader does it here): a regular file only, read within
a stated bound.

:func:`open_user_file` opens with ``O_NONBLOCK`` (a pipe with no writer does not hang),
refuses what is not a regular file and reads at most :func:`limit` bytes, *counting* them
(``st_size`` is not trusted); ``inside`` refuses a path whose real location leaves the folder
a reader was handed. Libraries that open a path themselves get it after
:func:`check_user_file`. Every refusal is an :class:`~cosim.errors.InputFileError` (exit 2)
naming the file and, when given, the key that named it.
"""

from __future__ import annotations

import io
import os
import stat
from pathlib import Path
from typing import Any, BinaryIO, TextIO

from .errors import InputFileError

MiB = 2**20
LIMITS: dict[str, int] = {
    "scenario": 4 * MiB,     # scenario / part / corner / sweep / duty TOML, a run's JSON
    "corner": 1 * MiB,       # vehicle.corner
    "tir": 4 * MiB,          # tyre.tir (a .tir is ~20 kB)
    "curve": 16 * MiB,       # controller.curve (damper force-velocity CSV)
    "profile": 256 * MiB,    # road.path CSV (~1e7 samples)
    "crg": 512 * MiB,        # road.path OpenCRG
    "mdf": 1024 * MiB,       # road.path / load file MDF 4
    "influence": 512 * MiB,  # fatigue.influence / fatigue.mapping case tables
    "mesh": 512 * MiB,       # a part's mesh (.inp, .msh, .vtu ...) and its *INCLUDEs
    "loads": 2048 * MiB,     # a load file (CSV / Parquet) for `suscosim fatigue`
    "fmu": 256 * MiB,        # controller.fmu (the zip itself; members: nodes.controller.fmu)
    "journal": 4096 * MiB,   # a run's journal.msgpack
    "report": 256 * MiB,     # a handed folder's JSON, CSV, log or image read whole by the report
}
"""Largest file read of each kind [bytes]; ``SUSCOSIM_MAX_<KIND>_MB`` overrides one."""

_KIND_OF_MODE = ((stat.S_ISDIR, "a folder"), (stat.S_ISCHR, "a character device"),
                 (stat.S_ISBLK, "a block device"), (stat.S_ISFIFO, "a named pipe (FIFO)"),
                 (stat.S_ISSOCK, "a socket"))


def limit(kind: str) -> int:
    env = f"SUSCOSIM_MAX_{kind.upper()}_MB"
    raw = os.environ.get(env)
    if raw is None:
        return LIMITS[kind]
    try:
        mb = float(raw)
    except ValueError:
        mb = -1.0
    if not 0 < mb < 2**40:
        raise InputFileError(env, f"environment variable: got {raw!r}, expected a positive "
                                  f"number of MiB")
    return int(mb * MiB)


def _where(key: str) -> str:
    return f"{key}: " if key else ""


def _check_inside(path: Path, inside: str | Path, key: str) -> None:
    real, folder = os.path.realpath(path), os.path.realpath(inside)
    if os.path.commonpath([real, folder]) != folder:
        raise InputFileError(str(path), f"{_where(key)}leaves the folder {str(inside)!r} "
                                        f"it was handed in (a symlink or '..')")


def _open_fd(path: str | Path, kind: str, key: str, inside: str | Path | None) -> int:
    if inside is not None:
        _check_inside(Path(path), inside, key)
    flags = os.O_RDONLY | os.O_NONBLOCK | os.O_NOCTTY | getattr(os, "O_CLOEXEC", 0)
    try:
        fd = os.open(path, flags)
    except FileNotFoundError:
        raise InputFileError(str(path), f"{_where(key)}file not found") from None
    except OSError as exc:
        raise InputFileError(str(path), f"{_where(key)}cannot open ({exc.strerror})") from None
    mode = os.fstat(fd).st_mode
    if not stat.S_ISREG(mode):
        os.close(fd)
        what = next((w for test, w in _KIND_OF_MODE if test(mode)), "not a plain file")
        raise InputFileError(str(path), f"{_where(key)}{what}, not a regular file")
    os.set_blocking(fd, True)
    return fd


def _too_big(path: str | Path, kind: str, key: str, cap: int) -> InputFileError:
    return InputFileError(str(path), f"{_where(key)}larger than the {cap / MiB:g} MiB read for "
                                     f"a {kind} file (SUSCOSIM_MAX_{kind.upper()}_MB raises it)")


class _Bounded(io.RawIOBase):
    """A raw stream over ``fd`` that raises once more than ``cap`` bytes are read."""

    def __init__(self, fd: int, path: str | Path, kind: str, key: str, cap: int) -> None:
        self._fd, self._path, self._kind, self._key, self._cap = fd, path, kind, key, cap
        self.count = 0

    def readable(self) -> bool:
        return True

    def readinto(self, b: memoryview) -> int:  # type: ignore[override]
        want = min(len(b), self._cap + 1 - self.count)
        if want <= 0:
            raise _too_big(self._path, self._kind, self._key, self._cap)
        data = os.read(self._fd, want)
        n = len(data)
        b[:n] = data
        self.count += n
        if self.count > self._cap:
            raise _too_big(self._path, self._kind, self._key, self._cap)
        return n

    def close(self) -> None:
        if not self.closed:
            os.close(self._fd)
        super().close()


def open_user_file(path: str | Path, kind: str, key: str = "",
                   inside: str | Path | None = None) -> BinaryIO:
    """A buffered binary stream of the regular file ``path`` (InputFileError past the limit)."""
    fd = _open_fd(path, kind, key, inside)
    return io.BufferedReader(_Bounded(fd, path, kind, key, limit(kind)))


def open_user_text(path: str | Path, kind: str, key: str = "", encoding: str = "utf-8",
                   inside: str | Path | None = None) -> TextIO:
    """:func:`open_user_file` as text (universal newlines off: ``newline=""``, for csv)."""
    return io.TextIOWrapper(open_user_file(path, kind, key, inside), encoding=encoding,
                            errors="strict", newline="")


def read_user_file(path: str | Path, kind: str, key: str = "",
                   inside: str | Path | None = None) -> bytes:
    """The bytes of the regular file ``path``, at most :func:`limit` of them."""
    with open_user_file(path, kind, key, inside) as fh:
        return fh.read()


def read_user_text(path: str | Path, kind: str, key: str = "", encoding: str = "utf-8",
                   inside: str | Path | None = None) -> str:
    """:func:`read_user_file` decoded (InputFileError naming a bad byte's offset)."""
    data = read_user_file(path, kind, key, inside)
    try:
        return data.decode(encoding)
    except UnicodeDecodeError as exc:
        raise InputFileError(str(path), f"{_where(key)}not a text ({encoding}) file: byte "
                                        f"{exc.start} is 0x{data[exc.start]:02x}") from None


MAX_TOML_DEPTH = 64  # nesting a user's TOML may have (a scenario: ~4; more: RecursionError)


def read_user_toml(path: str | Path, kind: str, key: str = "") -> dict[str, Any]:
    return parse_user_toml(read_user_text(path, kind, key), path, key)


def parse_user_toml(text: str, path: str | Path, key: str = "") -> dict[str, Any]:
    """The TOML ``text`` of ``path`` (InputFileError: invalid, or nested too deep)."""
    import tomllib

    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputFileError(str(path), f"{_where(key)}not valid TOML: {exc}") from None
    except RecursionError:
        data = None
    if data is None or _depth(data) > MAX_TOML_DEPTH:
        raise InputFileError(str(path), f"{_where(key)}tables or arrays nested deeper than "
                                        f"{MAX_TOML_DEPTH} levels")
    return data


def _depth(value: object) -> int:
    """The nesting depth of dicts and lists in ``value`` (no recursion; capped past the max)."""
    deepest, todo = 0, [(value, 1)]
    while todo:
        v, d = todo.pop()
        if isinstance(v, dict | list):
            deepest = max(deepest, d)
            if d <= MAX_TOML_DEPTH:
                todo.extend((c, d + 1) for c in (v.values() if isinstance(v, dict) else v))
    return deepest


def check_user_file(path: str | Path, kind: str, key: str = "",
                    inside: str | Path | None = None) -> int:
    """The size of the regular file ``path``, within :func:`limit` (before a library reads it)."""
    fd = _open_fd(path, kind, key, inside)
    try:
        size = os.fstat(fd).st_size
    finally:
        os.close(fd)
    cap = limit(kind)
    if size > cap:
        raise _too_big(path, kind, key, cap)
    return size
