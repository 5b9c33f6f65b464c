"""A one-line progress bar on stderr (a terminal only): ``starting nodes``, ``handshake`` (the
clock's start barrier, k = -1), any :meth:`ProgressBar.phase`, then the steps::

    ch3-step-... [###########...................]  37.2% step 1488/4000    2012 steps/s ETA 0:01

Rate and ETA count from the first step shown: ETA = (n - k) / rate.
"""

from __future__ import annotations

import sys
import time
from typing import TextIO


def format_eta(seconds: float) -> str:
    """``h:mm:ss`` (``m:ss`` under an hour) of a remaining time; ``--:--`` when unknown."""
    if not seconds >= 0 or seconds > 99 * 3600:
        return "--:--"
    s = int(round(seconds))
    h, rem = divmod(s, 3600)
    m, s = divmod(rem, 60)
    return f"{h}:{m:02d}:{s:02d}" if h else f"{m}:{s:02d}"


class ProgressBar:
    """The bar of one run, labelled ``label`` (the run id), on ``stream`` (stderr)."""

    def __init__(self, label: str, stream: TextIO | None = None, width: int = 30,
                 min_interval_s: float = 0.1, start_phase: str = "starting nodes",
                 quiet: bool = False) -> None:
        self.label, self.width = label, width
        self.stream = stream or sys.stderr
        self.enabled = self.stream.isatty() and not quiet
        self.min_interval_s = min_interval_s
        self.t0 = time.monotonic()
        self._last = 0.0
        self._first: tuple[float, int] | None = None  # (wall time, k) of the first step shown
        self._done_at: float | None = None  # wall time the last step was first shown
        self._width_written = 0
        self.phases: list[tuple[str, float]] = []  # start-up phases shown, their start [s]
        if start_phase:
            self.phase(start_phase)

    def _write(self, text: str) -> None:
        pad = max(0, self._width_written - len(text))  # clear what a longer line left
        self.stream.write("\r" + text + " " * pad)
        self.stream.flush()
        self._width_written = len(text)

    def phase(self, name: str, detail: str = "") -> None:
        """Show a start-up phase (``"handshake"``) with ``detail`` (``"3/4 nodes ready"``)."""
        if not self.phases or self.phases[-1][0] != name:
            self.phases.append((name, time.monotonic() - self.t0))
        if self.enabled:
            elapsed = time.monotonic() - self.t0
            self._write(f"{self.label} {name}{': ' + detail if detail else ''} ... {elapsed:.1f} s")

    def line(self, k: int, n: int, now: float) -> str:
        k = max(k, 0)
        if self._first is None:
            self._first = (now, k)
        t_first, k_first = self._first
        if k >= n:  # the rate of the steps, not of the wait for the table export after them
            self._done_at = self._done_at if self._done_at is not None else now
            now = self._done_at
        frac = max(0.0, min(1.0, (k + 1) / (n + 1)))
        fill = int(frac * self.width)
        dt = now - t_first
        rate = (k - k_first) / dt if dt > 0 else 0.0
        eta = format_eta((n - k) / rate) if rate > 0 else "--:--"
        return (f"{self.label} [{'#' * fill}{'.' * (self.width - fill)}] "
                f"{100 * frac:5.1f}% step {k}/{n} {rate:7.0f} steps/s ETA {eta}")

    def __call__(self, k: int, n: int) -> None:
        """Show step ``k`` of ``n``; ``k < 0``: the start barrier (``handshake``)."""
        if k < 0 and self._first is None:
            if not self.phases or self.phases[-1][0] != "handshake":
                self.phase("handshake")
            elif self.enabled and time.monotonic() - self._last >= self.min_interval_s:
                self._last = time.monotonic()
                self.phase("handshake")  # the seconds go on
            return
        now = time.monotonic()
        if self._first is None:
            self.line(k, n, now)  # the ETA's origin, even when not shown
        if not self.enabled or now - self._last < self.min_interval_s:
            return
        self._last = now
        self._write(self.line(k, n, now))

    def close(self) -> None:
        if self.enabled:
            self.stream.write("\n")
            self.stream.flush()

