"""Message fields as short text (the display) and as flat columns; ``--csv FILE``: data rows
appended to a CSV file whose header grows with the fields seen."""

from __future__ import annotations

import csv
import os
import tempfile
from pathlib import Path
from typing import Any, TextIO

from cosim.wire import Message

from .target import TapInputError


def fmt_value(value: Any, max_items: int = 4) -> str:
    """A number as %.5g; a list shortened to its first items and its length."""
    if isinstance(value, bool) or value is None:
        return str(value)
    if isinstance(value, int | float):
        return f"{value:.5g}"
    if isinstance(value, list | tuple):
        items = [fmt_value(v) for v in value[:max_items]]
        if len(value) > max_items:
            return "[" + ", ".join(items[:max_items - 1]) + f", ...]({len(value)})"
        return "[" + ", ".join(items) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k}: {fmt_value(v)}" for k, v in list(value.items())[:3]) + \
            (", ...}" if len(value) > 3 else "}")
    text = str(value)
    return text if len(text) <= 24 else text[:21] + "..."


def fmt_fields(msg: Message) -> str:
    body = " ".join(f"{name}={fmt_value(v)}" for name, v in msg.d.items())
    return body if msg.kind == "data" else f"<{msg.kind}> {body}".rstrip()


def flatten(d: dict[str, Any]) -> dict[str, Any]:
    """Data fields as CSV columns: a list ``x`` becomes ``x[0]``, ``x[1]``, ..."""
    out: dict[str, Any] = {}
    for name, value in d.items():
        if isinstance(value, list):
            for i, v in enumerate(value):
                out[f"{name}[{i}]"] = v
        else:
            out[name] = value
    return out


class CsvSink:
    """Append data rows to a CSV file whose header grows with the fields seen."""

    BASE = ["key", "k", "t"]

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.columns: list[str] = list(self.BASE)
        self.rows = 0
        try:
            with open(self.path, newline="") as f:
                header = next(csv.reader(f), None)
        except FileNotFoundError:
            header = None
        except OSError as exc:
            raise TapInputError(f"--csv {self.path}: {exc.strerror or exc}") from None
        if header:
            if header[:3] != self.BASE:
                raise TapInputError(f"--csv {self.path}: exists and is not a tap CSV "
                                    f"(header {','.join(header[:3])!r}, expected key,k,t)")
            self.columns = header
        try:
            self._f: TextIO = open(self.path, "a", newline="")
        except OSError as exc:
            raise TapInputError(f"--csv {self.path}: {exc.strerror or exc}") from None
        self._w = csv.writer(self._f)
        if not header:
            self._w.writerow(self.columns)

    def write(self, key: str, msg: Message) -> None:
        values = flatten(msg.d)
        new = [c for c in values if c not in self.columns]
        if new:
            self._widen(self.columns + new)
        row = {"key": key, "k": msg.k, "t": msg.t, **values}
        self._w.writerow([row.get(c, "") for c in self.columns])
        self.rows += 1

    def _widen(self, columns: list[str]) -> None:
        """Rewrite the file with a wider header (rare: a channel with new fields appeared)."""
        self._f.close()
        fd, tmp = tempfile.mkstemp(dir=self.path.parent, prefix=self.path.name, suffix=".tmp")
        with open(self.path, newline="") as src, os.fdopen(fd, "w", newline="") as dst:
            reader, writer = csv.reader(src), csv.writer(dst)
            next(reader, None)
            writer.writerow(columns)
            pad = [""] * (len(columns) - len(self.columns))
            for row in reader:
                writer.writerow(row + pad)
        os.replace(tmp, self.path)
        self.columns = columns
        self._f = open(self.path, "a", newline="")
        self._w = csv.writer(self._f)

    def flush(self) -> None:
        self._f.flush()

    def close(self) -> None:
        self._f.close()
