"""The coupling energy residual computed as the rows come, block by block (#29 item 1, #32).

:func:`cosim.coupling_energy.coupling_residual` needs the whole table; a run of an hour has
millions of rows. :class:`ResidualStream` takes the same columns in blocks of any size (the
row groups of ``table.parquet``, or the steps a live node has just recorded), keeps only the
few rows a step's residual reaches back to (``2 lag + 2``), and gives

* per block, the residual of every step it completed, per bond, ``dE`` [J] (the series a
  live view shows: the step ``k`` is complete once the force computed from the state at
  ``t_k+1`` has arrived, ``1 + lag`` rows later);
* at the end, the same :class:`~cosim.coupling_energy.BondResidual` totals as the whole-table
  computation (equal to rounding: the sums are taken in another order).

The columns are those :func:`~cosim.coupling_energy.coupling_residual` reads; a bond whose
columns the first block lacks is left out, as there.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .coupling_energy import BondResidual, _columns, applied_force, summary


@dataclass(frozen=True)
class BondSpec:
    """Which columns form a bond, and how its force behaves (as ``coupling_residual`` has it).

    ``force``/``slope``: the force node's output F [N] and its derivative; ``seen``: the
    plant variable the coupling linearises about; ``velocity``: the bond's velocity [m/s];
    a name ``a-b`` is the difference of two columns (v_rel = v_w - v_b).
    """

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


class ResidualStream:
    """Feed blocks of a run's rows in order (:meth:`feed`); :meth:`result` gives the totals.

    Args:
        h: the communication step [s]; ``coupling``: ``hold``, ``linear`` or ``jacobian``;
        exchange: ``sequential`` (lag 0) or ``parallel`` (lag 1).
    """

    def __init__(self, h: float, coupling: str, exchange: str) -> None:
        if not h > 0:
            raise ValueError(f"h = {h!r}: the communication step must be > 0 s")
        if coupling not in ("hold", "linear", "jacobian"):
            raise ValueError(f"unknown coupling {coupling!r}")
        self.h, self.coupling = float(h), coupling
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
        """Take the next rows; return, per bond, ``dE`` [J] (summed over corners) of the steps
        this block completed (in order; none for a block too short to complete one)."""
        if self.bonds is None:
            self.bonds = self._start(block)
        n_new = len(next(iter(block.values()))) if block else 0
        # the rows kept from before: every bond keeps as many; cur starts at global row g0
        g0 = self.rows - min((len(st.tail.get("F", ())) for st in self.bonds.values()),
                             default=0)
        out: dict[str, np.ndarray] = {}
        lag, h = self.lag, self.h
        for name, st in self.bonds.items():
            s = st.spec
            new = {"F": _get(block, s.force), "J": _get(block, s.slope),
                   "x": _get(block, s.seen), "v": _get(block, s.velocity)}
            cur = {key: np.concatenate([st.tail[key], a]) if key in st.tail else a
                   for key, a in new.items()}
            F, J, x, v = cur["F"], cur["J"], cur["x"], cur["v"]
            n_all = self.rows + n_new  # rows in the run so far
            # carried energy: rows j >= lag of this block, |F[j] v[j - lag]|
            j = np.arange(max(self.rows, lag), n_all) - g0
            st.carried += float(h * np.abs(F[j] * v[j - lag]).sum())
            # steps k completed: lag <= k, k + 1 + lag < n_all, not done before
            k_first = max(lag, self.rows - 1 - lag)
            k = np.arange(k_first, n_all - 1 - lag) - g0
            if k.size:
                F_k, J_k = F[k], J[k]
                F_prev = F[np.maximum(k - 1, -g0)]  # the run's row 0 has no previous
                seen = x[k - lag]
                app_start = applied_force(self.coupling, F_k, J_k, seen, x[k], F_prev, 0.0,
                                          s.clip, s.sign)
                app_end = applied_force(self.coupling, F_k, J_k, seen, x[k + 1], F_prev, 1.0,
                                        s.clip, s.sign)
                dE = 0.5 * h * ((app_start - F[k + lag]) * v[k]
                                + (app_end - F[k + 1 + lag]) * v[k + 1])
                st.abs_residual += float(np.abs(dE).sum())
                out[name] = dE.sum(axis=1)
            else:
                out[name] = np.zeros(0)
            st.tail = {key: a[-self._keep:] for key, a in cur.items()}
        self.rows += n_new
        return out

    def result(self) -> dict[str, BondResidual]:
        """The totals so far, per bond (``dE`` empty: the series came block by block)."""
        return {name: BondResidual(np.zeros(0), st.abs_residual, st.carried)
                for name, st in (self.bonds or {}).items()}


def residual_of_table_file(path: str | Path, h: float, coupling: str, exchange: str,
                           batch_rows: int = 65_536) -> dict[str, BondResidual]:
    """Both bonds' residual totals of a ``table.parquet``, read a row group at a time
    (memory independent of the run's length; :func:`cosim.table.iter_table`)."""
    from .table import iter_table

    stream = ResidualStream(h, coupling, exchange)
    for block in iter_table(path, keep=lambda c: c.split("[")[0] in COLUMNS,
                            batch_rows=batch_rows):
        stream.feed(block)
    return stream.result()


def summary_of_table_file(path: str | Path, h: float, coupling: str, exchange: str
                          ) -> dict[str, float]:
    """``summary.json``'s ``coupling_energy_residual`` of a ``table.parquet`` read in row
    groups (:func:`cosim.coupling_energy.summary`); ``{}`` for a run without either bond."""
    res = residual_of_table_file(path, h, coupling, exchange)
    return summary(res) if res else {}
