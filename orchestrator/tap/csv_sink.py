"""``--csv FILE``: data rows appended to a CSV file whose header grows with the fields seen."""

from __future__ import annotations

import csv
import os
import tempfile
from pathlib import Path
from typing import TextIO

from cosim.wire import Message

from .fmt import flatten
from .target import TapInputError


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
