"""What the tap saw per key (counts, rates, last message), its table and summary; message
fields as short text (the display) and as flat columns in ``--csv FILE`` (a CSV whose header
grows with the fields seen)."""

from __future__ import annotations

import csv
import json
import os
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO

from cosim import keys
from cosim.errors import WireError
from cosim.step_message import expand, is_step_key, matches
from cosim.wire import Message, decode

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
    return {k: v for name, value in d.items()
            for k, v in ([(f"{name}[{i}]", x) for i, x in enumerate(value)]
                         if isinstance(value, list) else [(name, value)])}


class CsvSink:
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


@dataclass
class RateWindow:
    """Messages counted since ``start`` [s]; ``rate``: that of the last closed window [msg/s]."""

    start: float
    count: int = 0
    rate: float = 0.0

    def close(self, now: float) -> None:
        if now > self.start:
            self.rate = self.count / (now - self.start)
        self.count, self.start = 0, now


@dataclass
class KeyStats:
    """What the tap saw on one key, first heard at ``first`` [s]."""

    first: float
    window: RateWindow
    count: int = 0
    undecodable: int = 0
    last: float = 0.0
    msg: Message | None = None
    problem: str = ""

    def seen(self, now: float, msg: Message) -> None:
        self.count += 1
        self.window.count += 1
        self.last, self.msg = now, msg

    def mean_rate(self) -> float:
        """Rate over the whole tap, first to last message [msg/s] (0 before two)."""
        if self.count > 1 and self.last > self.first:
            return (self.count - 1) / (self.last - self.first)
        return 0.0


@dataclass
class Tap:
    """Counts, last messages and rates per key; the display; the CSV."""

    keyexpr: str
    csv_sink: CsvSink | None = None
    raw: bool = False
    out: TextIO = sys.stdout
    stats: dict[str, KeyStats] = field(default_factory=dict)
    data: int = 0
    control: int = 0
    undecodable: int = 0
    last_problem: str = ""

    def handle(self, key: str, raw: bytes, now: float) -> Message | None:
        """Take one sample (a ``step``: the messages it carries); never raises on bad bytes."""
        if not is_step_key(key):
            return self._take(key, raw, now)
        msg = self._take(key, raw, now, count=False)
        if msg is None or msg.kind != "step":  # undecodable (counted), or a hello
            return self._seen(key, msg, now) if msg is not None and \
                matches(self.keyexpr, key) else None
        try:
            parts = expand(key, msg)
        except (WireError, ValueError) as exc:
            self._undecodable(key, now, str(exc), raw)
            return None
        last = None
        for vkey, one in parts:
            if matches(self.keyexpr, vkey):
                last = self._seen(vkey, one, now)
        return last

    def _take(self, key: str, raw: bytes, now: float, count: bool = True) -> Message | None:
        try:
            msg = decode(raw)
        except WireError as exc:
            self._undecodable(key, now, str(exc), raw)
            return None
        return self._seen(key, msg, now) if count else msg

    def _undecodable(self, key: str, now: float, problem: str, raw: bytes) -> None:
        st = self._stats(key, now)
        st.undecodable += 1
        self.undecodable += 1
        st.problem = self.last_problem = problem
        if self.raw:
            print(f"{_short_key(key)} UNDECODABLE ({problem}) {raw[:24].hex()}", file=self.out)

    def _stats(self, key: str, now: float) -> KeyStats:
        st = self.stats.get(key)
        if st is None:
            st = self.stats[key] = KeyStats(first=now, window=RateWindow(start=now))
        return st

    def _seen(self, key: str, msg: Message, now: float) -> Message:
        self._stats(key, now).seen(now, msg)
        if msg.kind == "data":
            self.data += 1
            if self.csv_sink is not None:
                self.csv_sink.write(key, msg)
        else:
            self.control += 1
        if self.raw:
            print(f"{_short_key(key)} {msg.kind} k={msg.k} t={msg.t:.6g} "
                  f"{json.dumps(msg.d, separators=(',', ':'), default=str)}", file=self.out)
        return msg

    def update_rates(self, now: float) -> None:
        for st in self.stats.values():
            st.window.close(now)

    def table(self, width: int = 0, final: bool = False) -> str:
        kw = max([len(_short_key(key)) for key in self.stats] + [24])
        lines = [f"{'key':<{kw}} {'count':>7} {'msg/s':>8} {'k':>7} {'t [s]':>9}  last values"]
        for key in sorted(self.stats):
            st = self.stats[key]
            rate = st.mean_rate() if final else st.window.rate
            msg = st.msg
            k = str(msg.k) if msg else "-"
            t = f"{msg.t:.4f}" if msg else "-"
            vals = fmt_fields(msg) if msg else ""
            if st.undecodable:
                vals = f"({st.undecodable} undecodable: {st.problem}) " + vals
            line = f"{_short_key(key):<{kw}} {st.count:>7} {rate:>8.1f} {k:>7} {t:>9}  {vals}"
            lines.append(line[:width or kw + 200])
        return "\n".join(lines)

    def summary(self) -> str:
        text = (f"tap: {self.data + self.control} messages ({self.data} data, {self.control} "
                f"control), {self.undecodable} undecodable on {len(self.stats)} key(s)")
        if self.undecodable:
            text += f"; last problem: {self.last_problem}"
        if self.csv_sink is not None:
            text += f"; {self.csv_sink.rows} rows -> {self.csv_sink.path}"
        return text


def _short_key(key: str) -> str:
    return key[len(keys.PREFIX) + 1:] if key.startswith(keys.PREFIX + "/") else key
