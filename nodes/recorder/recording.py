"""What the recorder does with each data message, without the bus: validate, journal,
tabulate. One copy, used by the recorder node's shell (:mod:`.node`, fed from the producers'
records batches) and by the one-process engine (:mod:`orchestrator.inprocess`, fed the same
messages directly), so both write the same journal records and the same table.

A data message must decode, be on a channel its node declared, and keep the layout of its
channel (the same fields, each a number or a list of one length, as in the channel's first
message); anything else is rejected (``reject``) and never journaled. A second message for a
step a channel already gave (a duplicate) is counted in ``duplicates`` and rejected. A hole in
a channel's steps sets :attr:`Recording.gap` (:func:`lost_steps`).

A fork with another law (``suscosim run --fork RUN@T --set controller.law=...``) records the
parent's steps < k and its own steps >= k in one table, but the two laws may publish other
fields on ``controller/force`` (skyhook's ``c``, an MR law's current): the table's columns of
such a channel are the union of both, a field one law does not publish NaN in its rows. The
new law's fields are known only at its first message (step k), so the parent's records of that
channel are held until then (:class:`ForkLayouts`; the other channels' rows wait in the table).
"""

from __future__ import annotations

import errno
from bisect import bisect_right
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any

from cosim import channels as ch
from cosim.coupling_stream import LiveResidual
from cosim.errors import RunError, WireError
from cosim.journal import JournalWriter
from cosim.run_settings import RunSettings
from cosim.table_writer import TableWriter
from cosim.wire import Message, codec

EARLY_MAX = 100_000
"""Data messages held before the clock's start says which channels the run has."""
STATE_CHANNEL = f"{ch.PLANT}/{ch.STATE}"
"""The channel whose time says which step is the run's last (:meth:`RunSettings.is_last`)."""

Reject = Callable[[tuple[str, str], str], None]


class Recording:
    """One run's journal and table as the data messages come (see the module's docstring).

    ``reject((node, channel), why)`` is told every message not journaled. :meth:`begin`
    (once the start says which channels the run has) opens the table; messages before are
    held. ``live``: also compute the live coupling residual (:attr:`live`)."""

    def __init__(self, scenario: dict[str, Any], journal: JournalWriter, reject: Reject,
                 start_k: int = 0, live: bool = True) -> None:
        run_cfg = scenario["run"]
        self.folder = Path(run_cfg["dir"])
        self.journal, self.reject, self._want_live = journal, reject, live
        self.settings = RunSettings.of(scenario)
        self.run_cfg = run_cfg
        self.expected: set[str] = set()
        self.got: dict[str, StepSet] = {}
        self.table: TableWriter | None = None
        self.live: LiveResidual | None = None
        self.early: list[tuple[str, str, bytes, Message]] = []
        self.n_steps: int | None = None
        self.duplicates = 0
        self.last: tuple[int, float] | None = None  # (k, t) of the run's last step, once known
        self.gap: str | None = None  # why the run cannot complete: a batch that never came
        self.fork = ForkLayouts((run_cfg.get("resume") or {}).get("fresh", ()), start_k)

    def begin(self, n_steps: int, channels: Iterable[str]) -> None:
        """The run's N and its per-step channels (``node/channel``): the table opens."""
        self.n_steps = n_steps
        self.expected.update(channels)
        self.got.update((c, StepSet()) for c in self.expected)
        if self.expected:
            self.table = TableWriter(self.expected, self.folder)
            self.live = _live_residual(self.run_cfg, self.expected) if self._want_live \
                else None

    def release_early(self) -> None:
        """The messages held before :meth:`begin`, recorded."""
        early, self.early = self.early, []
        for node, channel, raw, msg in early:
            self.record(node, channel, raw, msg)

    def record(self, node: str, channel: str, raw: bytes, msg: Message | None = None) -> None:
        """Validate, journal and tabulate one data message of ``node/channel``."""
        if msg is None:  # checked against its channel's schema (cosim/schema.py)
            try:
                msg = codec(f"{node}/{channel}").decode(raw)
            except WireError as exc:
                self.reject((node, channel), str(exc))
                return
        if msg.kind != "data" or msg.k < 0:
            return
        if self.table is None:  # before the start: which channels the run has is not known
            if len(self.early) < EARLY_MAX:
                self.early.append((node, channel, raw, msg))
            else:
                self.reject((node, channel), "data before the run's start")
            return
        name = f"{node}/{channel}"
        if self.n_steps is not None and msg.k > self.n_steps:
            self.reject((node, channel), f"step {msg.k} after the last step {self.n_steps}")
            return
        steps = self.got.get(name)
        if steps is None:
            self.reject((node, channel), f"{name} is not an output {node} declared")
            return
        if msg.k in steps:
            self.duplicates += 1
            self.reject((node, channel), f"step {msg.k} again (a duplicate: not journaled)")
            return
        fork = self.fork
        if fork.holds(node, msg.k):  # a fork's new law: its layout is known at step k
            fork.hold(name, msg.k, msg.t, msg.d)
        else:
            if name in fork.held:
                try:
                    for k, t, d in fork.release(name, msg.d):
                        self.tabulate(name, k, t, d)
                except ValueError as exc:
                    raise RunError(f"recorder: the fork's table: {exc}") from None
            wrong = self.tabulate(name, msg.k, msg.t, fork.pad(name, msg.d))
            if wrong:
                self.reject((node, channel), wrong)
                return
        steps.add(msg.k)
        if self.gap is None and len(steps.lo) > 1:  # a producer sends in order: a hole
            self.gap = lost_steps(node, name, steps)
        self.journal.append(name, raw)
        if name == STATE_CHANNEL and self.settings.is_last(msg.k, msg.t):
            self.last = (msg.k, msg.t)

    def tabulate(self, name: str, k: int, t: float, d: Any) -> str | None:
        """Put one message in the table (and the live residual); why not, else None."""
        table = self.table
        assert table is not None
        rows = table.rows
        wrong = table.add(name, k, t, d)
        if wrong:
            return wrong
        if self.live is not None:
            self.live.add(name, k, t, d)
            if table.rows > rows:  # this message completed the row of its step
                self.live.row(k)
        return None

    def done_k(self) -> int:
        """The last step every channel has delivered."""
        return min(self.got[c].count for c in self.expected) - 1

    @property
    def complete(self) -> bool:
        """Every channel has given every step up to the run's last."""
        return self.last is not None and bool(self.expected) and \
            self.done_k() >= self.last[0]

    def finish_table(self) -> dict[str, Any]:
        """The table in place: the recorder's result (stats, files, rows)."""
        assert self.table is not None
        files = self.table.close()
        return {"stats": self.table.stats(), "files": files, "rows": self.table.rows,
                "torn": False, "undecodable": 0, "duplicates": self.duplicates}


def lost_steps(node: str, name: str, steps: StepSet) -> str:
    """The run's error for the first hole in the steps channel ``name`` delivered: a producer
    sends its batches in step order and Zenoh delivers them reliably and in order, so steps
    missing below one that came were lost on the bus or rejected here, and nothing sends them
    again (waiting for the stall timeout would only hide which steps and whose batch)."""
    lo, hi = steps.hi[0], steps.lo[1] - 1
    return (f"recorder: {name} steps {lo}-{hi} never arrived (a records batch of {node!r} "
            f"was lost on the bus or rejected; its step {steps.lo[1]} came): the journal "
            f"holds the steps before")


def _live_residual(run_cfg: dict[str, Any], channels: set[str]) -> LiveResidual | None:
    """The live residual of the run's table (None: a scenario without its ``coupling`` and
    ``exchange``, which a resolved scenario always has, says nothing to compute it by)."""
    if "coupling" not in run_cfg or "exchange" not in run_cfg:
        return None
    h = None if run_cfg.get("adaptive") else float(run_cfg["h"])  # None: each step's from t
    return LiveResidual(h, run_cfg["coupling"], run_cfg["exchange"], channels)


def write_error(exc: OSError, folder: Any) -> RunError:
    """The run's error for a journal or table that could not be written (a full disk)."""
    full = " (the disk is full)" if exc.errno == errno.ENOSPC else ""
    return RunError(f"recorder: cannot write the run's journal or table in {folder}: "
                    f"{exc.strerror or exc}{full}")


class StepSet:
    """Steps ``k`` >= 0 received, as half-open ranges ``[lo, hi)``; ``count`` of them."""

    __slots__ = ("lo", "hi", "count")

    def __init__(self) -> None:
        self.lo: list[int] = []
        self.hi: list[int] = []
        self.count = 0

    def add(self, k: int) -> bool:
        """Add step ``k``; False when it was already there (a duplicate)."""
        lo, hi = self.lo, self.hi
        if hi and k == hi[-1]:  # the usual case: the next step in order
            hi[-1] += 1
            self.count += 1
            return True
        i = bisect_right(lo, k) - 1  # the range starting at or before k
        if i >= 0 and k < hi[i]:
            return False
        joins_left = i >= 0 and hi[i] == k
        joins_right = i + 1 < len(lo) and lo[i + 1] == k + 1
        if joins_left and joins_right:
            hi[i] = hi[i + 1]
            del lo[i + 1], hi[i + 1]
        elif joins_left:
            hi[i] = k + 1
        elif joins_right:
            lo[i + 1] = k
        else:
            lo.insert(i + 1, k)
            hi.insert(i + 1, k + 1)
        self.count += 1
        return True

    def __contains__(self, k: int) -> bool:
        i = bisect_right(self.lo, k) - 1
        return i >= 0 and k < self.hi[i]


class ForkLayouts:
    """Which records a fork holds back, and the NaN-padded union layout of their channels."""

    def __init__(self, fresh_nodes: Iterable[str], start_k: int) -> None:
        self.fresh = frozenset(fresh_nodes)
        self.start_k = int(start_k)
        self.held: dict[str, list[tuple[int, float, Mapping[str, Any]]]] = {}
        self._fill: dict[str, dict[str, Any]] = {}

    def holds(self, node: str, k: int) -> bool:
        """A record of the parent's prefix (k < start) of a node that starts afresh."""
        return k < self.start_k and node in self.fresh

    def hold(self, name: str, k: int, t: float, d: Mapping[str, Any]) -> None:
        self.held.setdefault(name, []).append((k, t, d))

    def release(self, name: str, first: Mapping[str, Any]
                ) -> list[tuple[int, float, Mapping[str, Any]]]:
        """The held records of ``name`` padded to the union of their fields and those of the
        new node's ``first`` message (which :meth:`pad` pads from then on); ValueError when a
        field is a number in one and a list (or another length) in the other."""
        held = self.held.pop(name, [])
        shapes: dict[str, int | None] = {}
        for d in (*(d for _k, _t, d in held), first):
            for f, v in d.items():
                n = len(v) if type(v) is list else None
                if shapes.setdefault(f, n) != n:
                    raise ValueError(f"{name}: field {f!r} is {_shape(shapes[f])} in the parent "
                                     f"and {_shape(n)} in the fork")
        self._fill[name] = {f: float("nan") if n is None else [float("nan")] * n
                            for f, n in shapes.items()}
        return [(k, t, self.pad(name, d)) for k, t, d in held]

    def pad(self, name: str, d: Mapping[str, Any]) -> Mapping[str, Any]:
        """``d`` with the union's missing fields as NaN (``d`` itself for other channels)."""
        fill = self._fill.get(name)
        if fill is None or len(d) == len(fill):
            return d
        return {**fill, **d}


def _shape(n: int | None) -> str:
    return "a number" if n is None else f"a list of {n}"
