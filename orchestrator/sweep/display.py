"""One progress display for the whole sweep on stderr."""

from __future__ import annotations

import time
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Protocol, TextIO

from cosim.run_folder import read_json

from .results import _fmt

if TYPE_CHECKING:
    from .spec import Point


class Job(Protocol):
    """A point being worked on (a local process or a Dask task)."""

    point: Point
    phase: str
    t0: float
    fresh: bool

    def step(self) -> int | None:
        ...


class Display:
    """A line per running point, redrawn on a terminal; on a pipe, events and a status."""

    def __init__(self, stream: TextIO, total: int, n_steps_total: int) -> None:
        self.stream, self.total = stream, total
        self.tty = stream.isatty()
        self.lines = 0
        self.t0 = time.monotonic()
        self.last_status = self.t0
        self.n_steps_total = max(1, n_steps_total)

    def _clear(self) -> None:
        if self.tty and self.lines:
            self.stream.write(f"\x1b[{self.lines}F\x1b[J")
            self.lines = 0

    def event(self, text: str) -> None:
        self._clear()
        self.stream.write(text + "\n")
        self.stream.flush()

    def update(self, jobs: Sequence[Job], done: int, failed: int, pending: int,
               steps_done: int) -> None:
        elapsed = time.monotonic() - self.t0
        if not self.tty and time.monotonic() - self.last_status < 30.0:
            return
        steps = steps_done + sum((j.step() or 0) if j.phase == "run" else j.point.n_steps
                                 for j in jobs if j.phase == "run" or j.fresh)
        head = (f"sweep: {done}/{self.total} finished ({failed} failed), {len(jobs)} running, "
                f"{pending} waiting; {100 * min(1.0, steps / self.n_steps_total):3.0f}% of "
                f"the steps, {elapsed:5.0f} s")
        if not self.tty:
            self.last_status = time.monotonic()
            parts = [f"{j.point.id} {self._frac(j)}" for j in jobs]
            self.stream.write(head + (": " + ", ".join(parts) if parts else "") + "\n")
            self.stream.flush()
            return
        width = max((len(j.point.id) for j in jobs), default=0)
        rows = [head]
        for j in jobs:
            rows.append(f"  {j.point.id:<{width}}  {self._bar(j)}")
        self._clear()
        self.stream.write("\n".join(rows) + "\n")
        self.stream.flush()
        self.lines = len(rows)

    def _frac(self, j: Job) -> str:
        if j.phase != "run":
            return j.phase
        k = j.step()
        return "starting" if k is None else f"{100 * k / max(1, j.point.n_steps):.0f}%"

    def _bar(self, j: Job) -> str:
        t = time.monotonic() - j.t0
        if j.phase != "run":
            return f"{j.phase:<8} {t:6.0f} s"
        k = j.step()
        if k is None:
            return f"starting {t:6.0f} s"
        n = max(1, j.point.n_steps)
        frac = min(1.0, max(0.0, k / n))
        fill = int(frac * 24)
        return (f"run [{'#' * fill}{'.' * (24 - fill)}] {100 * frac:5.1f}% step {k}/{n} {t:6.0f} s")

    def close(self) -> None:
        self._clear()


def event_line(run_dir: Path, pid: str, status: str, err: str, i: int, n: int) -> str:
    head = f"[{i}/{n}] {status:<6} {pid}"
    if status != "ok":
        return f"{head}: {err}"
    s = read_json(run_dir / "summary.json") or {}
    text = f"{head}  wall {s.get('wall_s', 0):.1f} s, {s.get('steps_per_s', 0):.0f} steps/s"
    f = read_json(run_dir / "fatigue" / "summary.json")
    if isinstance(f, dict):
        text += f", min life {_fmt(f.get('min_life_km'))} km"
    return text
