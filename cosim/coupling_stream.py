"""The coupling energy residual (:mod:`cosim.coupling_energy`) computed block by block.

:class:`ResidualStream` takes a run's table in blocks of any size (the row groups of
``table.parquet``, or the steps a live node has just recorded), keeps only the rows a step's
residual reaches back to (``2 lag + 2``), and gives per block each bond's ``dE`` [J] of the
steps it completed (step ``k`` is complete ``1 + lag`` rows later, once the force computed
from the state at ``t_k+1`` has arrived), and at the end the
:class:`~cosim.coupling_energy.BondResidual` totals. A bond whose columns the first block
lacks is left out.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .coupling_energy import BondResidual, _columns, applied_force, summary


@dataclass(frozen=True)
class BondSpec:
    """A bond's columns: ``force`` F [N], ``slope`` dF/dx, ``seen`` the plant variable the
    coupling linearises about, ``velocity`` [m/s] (``a-b``: a difference)."""

    force: str
    slope: str
    seen: str
    velocity: str
    clip: bool
    sign: float


BOND_SPECS: dict[str, BondSpec] = {
    "damper": BondSpec("controller/force/F_d", "controller/force/c_eff",
                       "plant/state/v_w-plant/state/v_b", "plant/state/v_w-plant/state/v_b",
                       clip=False, sign=1.0),
    "tyre": BondSpec("tyre_road/force/F_t", "tyre_road/force/k_t", "plant/state/z_w",
                     "plant/state/v_w", clip=True, sign=-1.0),
}
COLUMNS = ("plant/state/v_w", "plant/state/v_b", "plant/state/z_w", "controller/force/F_d",
           "controller/force/c_eff", "tyre_road/force/F_t", "tyre_road/force/k_t")


def _get(block: Mapping[str, np.ndarray], name: str) -> np.ndarray:
    if "-" in name:
        a, b = name.split("-")
        diff: np.ndarray = _columns(block, a) - _columns(block, b)
        return diff
    return _columns(block, name)


@dataclass
class _BondState:
    spec: BondSpec
    tail: dict[str, np.ndarray] = field(default_factory=dict)  # F, J, x, v: last rows
    abs_residual: float = 0.0
    carried: float = 0.0

    def rows(self, block: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
        """F, J, x, v of the rows kept from before and ``block``'s."""
        s = self.spec
        new = {"F": _get(block, s.force), "J": _get(block, s.slope),
               "x": _get(block, s.seen), "v": _get(block, s.velocity)}
        return {key: np.concatenate([self.tail[key], a]) if key in self.tail else a
                for key, a in new.items()}


class ResidualStream:
    """Feed blocks of rows in order (:meth:`feed`); :meth:`result` gives the totals. ``h``
    [s], or None for an adaptive step (each step's length from the rows' ``t``)."""

    def __init__(self, h: float | None, coupling: str, exchange: str) -> None:
        if h is not None and not h > 0:
            raise ValueError(f"h = {h!r}: the communication step must be > 0 s")
        if coupling not in ("hold", "linear", "jacobian"):
            raise ValueError(f"unknown coupling {coupling!r}")
        self.h, self.coupling = (None if h is None else float(h)), coupling
        self._t_tail = np.zeros(0)  # adaptive: the last rows' t [s]
        self.lag = 0 if exchange == "sequential" else 1
        self.rows = 0  # rows fed so far
        self.bonds: dict[str, _BondState] | None = None
        self._keep = 2 * self.lag + 2  # rows a step reaches back to (F_prev at k - 1)

    def _start(self, block: Mapping[str, np.ndarray]) -> dict[str, _BondState]:
        bonds = {}
        for name, spec in BOND_SPECS.items():
            try:
                for col in (spec.force, spec.slope, spec.seen, spec.velocity):
                    _get(block, col)
            except KeyError:
                continue
            bonds[name] = _BondState(spec)
        return bonds

    def feed(self, block: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Per bond, ``dE`` [J] (summed over corners) of the steps this block completed."""
        if self.bonds is None:
            self.bonds = self._start(block)
        n_new = len(next(iter(block.values()))) if block else 0
        # the rows kept from before: every bond keeps as many; cur starts at global row g0
        g0 = self.rows - min((len(st.tail.get("F", ())) for st in self.bonds.values()),
                             default=0)
        lag, h, n_all = self.lag, self.h, self.rows + n_new
        # carried energy: rows j >= lag of this block, |F[j] v[j - lag]|; steps k completed:
        # lag <= k, k + 1 + lag < n_all, not done before
        j = np.arange(max(self.rows, lag), n_all) - g0
        k = np.arange(max(lag, self.rows - 1 - lag), n_all - 1 - lag) - g0
        if h is None:  # an adaptive step: each step's length from the rows' t
            tt = np.concatenate([self._t_tail, np.asarray(block["t"], dtype=np.float64)])
            back = np.where(j + g0 > 0, j - 1, j + 1)  # the step that ends at row j
            hj = np.abs(tt[j] - tt[np.clip(back, 0, len(tt) - 1)])[:, None]
            hk = (tt[k + 1] - tt[k])[:, None]
            hprev = np.where(k + g0 > 0, tt[k] - tt[np.maximum(k - 1, 0)], hk[:, 0])
            r_end = hk / np.where(hprev > 0, hprev, hk[:, 0])[:, None]
            self._t_tail = tt[-self._keep:]
        out: dict[str, np.ndarray] = {}
        for name, st in self.bonds.items():
            cur = st.rows(block)
            F, v = cur["F"], cur["v"]
            if h is None:
                st.carried += float((hj * np.abs(F[j] * v[j - lag])).sum())
                out[name] = self._steps(st, cur, k, g0, hk, r_end)
            else:
                st.carried += float(h * np.abs(F[j] * v[j - lag]).sum())
                out[name] = self._steps(st, cur, k, g0, h, 1.0)
            st.tail = {key: a[-self._keep:] for key, a in cur.items()}
        self.rows += n_new
        return out

    def _steps(self, st: _BondState, cur: Mapping[str, np.ndarray], k: np.ndarray, g0: int,
               h: float | np.ndarray, r_end: float | np.ndarray) -> np.ndarray:
        """dE [J] of the steps ``k`` (rows of ``cur``; the run's row 0 at ``-g0``), of length
        ``h`` [s] (one, or a column); ``r_end``: the step's end over the previous step's."""
        if not k.size:
            return np.zeros(0)
        s, lag = st.spec, self.lag
        F, J, x, v = cur["F"], cur["J"], cur["x"], cur["v"]
        F_k, J_k = F[k], J[k]
        F_prev = F[np.maximum(k - 1, -g0)]  # the run's row 0 has no previous
        seen = x[k - lag]
        app_start = applied_force(self.coupling, F_k, J_k, seen, x[k], F_prev, 0.0,
                                  s.clip, s.sign)
        app_end = applied_force(self.coupling, F_k, J_k, seen, x[k + 1], F_prev, r_end,
                                s.clip, s.sign)
        dE = 0.5 * h * ((app_start - F[k + lag]) * v[k] + (app_end - F[k + 1 + lag]) * v[k + 1])
        st.abs_residual += float(np.abs(dE).sum())
        return np.asarray(dE.sum(axis=1))

    def result(self) -> dict[str, BondResidual]:
        """The totals so far, per bond (``dE`` empty)."""
        return {name: BondResidual(np.zeros(0), st.abs_residual, st.carried)
                for name, st in (self.bonds or {}).items()}


def residual_of_table_file(path: str | Path, h: float | None, coupling: str, exchange: str,
                           batch_rows: int = 65_536) -> dict[str, BondResidual]:
    """Both bonds' residual totals of a ``table.parquet``, read a row group at a time."""
    from .formats.stream import iter_chunks, table_columns

    stream = ResidualStream(h, coupling, exchange)
    names = [c for c in table_columns(path) if c in ("k", "t") or c.split("[")[0] in COLUMNS]
    for block in iter_chunks(path, names, batch_rows):
        stream.feed(block)
    return stream.result()


def summary_of_table_file(path: str | Path, h: float | None, coupling: str, exchange: str
                          ) -> dict[str, float]:
    """``summary.json``'s ``coupling_energy_residual`` of a ``table.parquet`` ({}: no bond)."""
    res = residual_of_table_file(path, h, coupling, exchange)
    return summary(res) if res else {}


# ---- the live channel: recorder/coupling ----------------------------------------------------
MAX_STEPS = 1024
"""Steps of ``dE`` in one ``recorder/coupling`` message at most: two bonds' (n,) lists of
float64 are ~18 KB, inside :data:`cosim.wire.MAX_MESSAGE_BYTES` (48 KB) with room to spare."""
_FIELDS: dict[str, tuple[str, ...]] = {}
for _col in COLUMNS:  # the channels the residual reads, and their fields
    _chan, _, _fld = _col.rpartition("/")
    _FIELDS[_chan] = (*_FIELDS.get(_chan, ()), _fld)
BOND_CHANNELS = tuple(_FIELDS)
"""``plant/state``, ``controller/force``, ``tyre_road/force``: what the residual reads."""


class LiveResidual:
    """The residual of a run as its table's rows complete, cut into the messages of the
    ``recorder/coupling`` channel (docs/coupling_residual.md): the recorder gives it each data
    message it tabulates (:meth:`add`) and each row the table wrote (:meth:`row`); :meth:`take`
    feeds the new rows in blocks of at most :data:`MAX_STEPS`, a message per block."""

    def __init__(self, h: float | None, coupling: str, exchange: str,
                 channels: Iterable[str]) -> None:
        from .coupling_energy import WARNING_THRESHOLD

        self.stream = ResidualStream(h, coupling, exchange)
        have = set(channels)
        self.channels = tuple(c for c in BOND_CHANNELS if c in have)
        self.threshold = WARNING_THRESHOLD
        self._held: dict[int, dict[str, Mapping[str, Any]]] = {}  # step -> channel -> fields
        self._t: dict[int, float] = {}  # step -> plant/state's t [s]
        self._rows: list[tuple[int, float, dict[str, Mapping[str, Any]]]] = []
        self._last_row = -1
        self._ks: deque[tuple[int, float]] = deque()  # (k, t) of rows fed, step not given yet
        self._next = self.stream.lag  # row index of the next step to give (rows 0..lag-1: none)
        self._first = 0  # row index of _ks[0]

    def add(self, channel: str, k: int, t: float, d: Mapping[str, Any]) -> None:
        """A data message the table took (``channel`` = ``node/channel``)."""
        if channel not in self.channels or k <= self._last_row:
            return
        held = self._held.get(k)
        if held is None:
            held = self._held[k] = {}
        held[channel] = d  # the message's own fields (kept until its row, not copied)
        if channel == "plant/state":
            self._t[k] = t

    def row(self, k: int) -> None:
        """The table wrote the row of step ``k`` (rows come in increasing ``k``)."""
        self._last_row = k
        self._rows.append((k, self._t.pop(k, 0.0), self._held.pop(k, {})))

    @property
    def held(self) -> int:
        """Steps held whose row is not written (yet, or ever)."""
        return len(self._held)

    @property
    def pending(self) -> int:
        """Rows complete, not yet fed by :meth:`take`."""
        return len(self._rows)

    def take(self) -> list[tuple[int, float, dict[str, Any]]]:
        """Feed the rows complete so far; the messages to publish, (last k, its t [s], payload)."""
        rows, self._rows = self._rows, []
        for j in [j for j in self._held if j < self._last_row]:  # never rows now: the
            del self._held[j]  # table dropped them (a channel's message came too late)
            self._t.pop(j, None)
        out: list[tuple[int, float, dict[str, Any]]] = []
        for i in range(0, len(rows), MAX_STEPS):
            part = rows[i:i + MAX_STEPS]
            self._ks.extend((k, t) for k, t, _ in part)
            dE = self.stream.feed(_block(part, self.channels))
            n = len(next(iter(dE.values()))) if dE else 0
            done = [self._ks[j - self._first] for j in range(self._next, self._next + n)]
            self._next += n
            while self._first < self._next and self._ks:  # keep the rows not yet given
                self._ks.popleft()
                self._first += 1
            if n:
                out += _messages(done, dE, self.stream.result(), self.threshold)
        return out


def _block(rows: list[tuple[int, float, dict[str, Mapping[str, Any]]]],
           channels: tuple[str, ...]) -> dict[str, np.ndarray]:
    """The rows' bond columns, named as the table names them (``v_w`` or ``v_w[i]``)."""
    block: dict[str, np.ndarray] = {"t": np.asarray([r[1] for r in rows], dtype=np.float64)}
    for chan in channels:
        for fld in _FIELDS[chan]:
            a = np.asarray([r[2][chan][fld] for r in rows], dtype=np.float64)
            name = f"{chan}/{fld}"
            if a.ndim == 1:
                block[name] = a
            else:
                for i in range(a.shape[1]):
                    block[f"{name}[{i}]"] = np.ascontiguousarray(a[:, i])
    return block


def _messages(done: list[tuple[int, float]], dE: Mapping[str, np.ndarray],
              totals: Mapping[str, BondResidual], threshold: float
              ) -> list[tuple[int, float, dict[str, Any]]]:
    """One message per run of consecutive steps in ``done``."""
    ks = np.asarray([k for k, _ in done])
    cuts = [0, *(np.flatnonzero(np.diff(ks) != 1) + 1).tolist(), len(ks)]
    return [(int(ks[b - 1]), done[b - 1][1],
             message(int(ks[a]), {n: v[a:b] for n, v in dE.items()}, totals, threshold))
            for a, b in zip(cuts[:-1], cuts[1:], strict=True)]


def message(k0: int, dE: Mapping[str, np.ndarray], totals: Mapping[str, BondResidual],
            threshold: float) -> dict[str, Any]:
    """The payload of one ``recorder/coupling`` message of steps ``k0 ..`` (:mod:`cosim.schema`)."""
    d: dict[str, Any] = {"k0": int(k0)}
    for name, v in dE.items():
        d[f"dE_{name}"] = [float(x) for x in v]
    for name, r in totals.items():
        d[f"res_{name}"], d[f"carried_{name}"] = r.abs_residual, r.carried
    for name, rel in summary(totals).items():
        d[f"rel_{name}"] = rel
    d["threshold"] = float(threshold)
    return d
