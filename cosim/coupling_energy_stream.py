"""The coupling energy residual (:mod:`cosim.coupling_energy`) of a run's ``table.parquet``
read in row batches (#32): the orchestrator's memory at the end of a run does not grow with
the run (it read the bonds' eight columns whole: 223 MB peak at 10^5 steps, 471 MB at 10^6).

Each bond's per-step residual is :func:`cosim.coupling_energy.bond_residual`'s formula on a
window of rows (a batch and the few rows before it that steps k - 1 - lag .. k + 1 + lag
need); the sums |dE| and h |F v| are accumulated batch by batch, so they equal the whole
table's to the last few bits (a sum in another order; the per-step terms are the same).
Only the totals are kept (``summary.json`` holds the relative residuals, not ``dE``).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from pathlib import Path

import numpy as np

from .coupling_energy import _columns, applied_force

COLUMNS = ("plant/state/v_w", "plant/state/v_b", "plant/state/z_w", "controller/force/F_d",
           "controller/force/c_eff", "tyre_road/force/F_t", "tyre_road/force/k_t")
"""The bases of the columns the two bonds use (``name`` or ``name[i]`` per corner)."""


class _Bond:
    """Running sums of one bond: sum |dE| [J], sum h |F v| [J], over steps as rows arrive."""

    def __init__(self, h: float, coupling: str, lag: int, clip: bool, sign: float,
                 n: int) -> None:
        self.h, self.coupling, self.lag, self.clip, self.sign, self.n = \
            h, coupling, lag, clip, sign, n
        self.m = n - 1 - 2 * lag  # steps k = lag .. lag + m - 1
        self.k_next = lag  # next step to add
        self.j_next = lag  # next row of the carried energy (F[j] v[j - lag])
        self.abs_residual = 0.0
        self.carried = 0.0

    def add(self, g0: int, F: np.ndarray, J: np.ndarray, x: np.ndarray, v: np.ndarray
            ) -> int:
        """Rows g0 .. g0 + len(F) - 1 of the bond's columns; the first row still needed."""
        g1 = g0 + F.shape[0]
        lag = self.lag
        # carried: rows j with j - lag >= g0 and j < g1
        j = np.arange(max(self.j_next, g0 + lag), g1)
        if j.size:
            self.carried += float(self.h * np.abs(F[j - g0] * v[j - lag - g0]).sum())
            self.j_next = int(j[-1]) + 1
        # steps k: k - 1 >= g0 (or k = 0), k - lag >= g0, k + 1 + lag < g1, k < lag + m
        k_lo = self.k_next
        k_hi = min(g1 - 1 - lag, lag + max(self.m, 0))
        if k_hi > k_lo and self.m > 0:
            k = np.arange(k_lo, k_hi)
            i = k - g0
            F_k, J_k = F[i], J[i]
            F_prev = F[np.maximum(k - 1, 0) - g0]
            seen = x[i - lag]
            true_start, true_end = F[i + lag], F[i + 1 + lag]
            a0 = applied_force(self.coupling, F_k, J_k, seen, x[i], F_prev, 0.0, self.clip,
                               self.sign)
            a1 = applied_force(self.coupling, F_k, J_k, seen, x[i + 1], F_prev, 1.0, self.clip,
                               self.sign)
            dE = 0.5 * self.h * ((a0 - true_start) * v[i] + (a1 - true_end) * v[i + 1])
            self.abs_residual += float(np.abs(dE).sum())
            self.k_next = k_hi
        return max(0, min(self.k_next - 1 - lag, self.j_next - lag))

    @property
    def relative(self) -> float:
        return self.abs_residual / self.carried if self.carried > 0 else 0.0


def _batches(path: Path, names: list[str]) -> Iterator[dict[str, np.ndarray]]:
    from .table_batches import parquet_batches

    yield from parquet_batches(path, names)


def coupling_summary(path: str | Path, h: float, coupling: str, exchange: str
                     ) -> dict[str, float]:
    """``summary.json``'s ``coupling_energy_residual`` (:func:`cosim.coupling_energy.summary`)
    of ``table.parquet`` at ``path``, read in batches; ``{}`` without the bonds' columns."""
    import pyarrow.parquet as pq

    path = Path(path)
    f = pq.ParquetFile(path)
    names = [c for c in f.schema_arrow.names if c.split("[")[0] in COLUMNS]
    n = int(f.metadata.num_rows)
    have = {c.split("[")[0] for c in names}
    if not {"plant/state/v_w", "plant/state/v_b"} <= have:
        return {}
    lag = 0 if exchange == "sequential" else 1
    bonds: dict[str, _Bond] = {}
    if {"controller/force/F_d", "controller/force/c_eff"} <= have:
        bonds["damper"] = _Bond(h, coupling, lag, clip=False, sign=1.0, n=n)
    if {"tyre_road/force/F_t", "tyre_road/force/k_t", "plant/state/z_w"} <= have:
        bonds["tyre"] = _Bond(h, coupling, lag, clip=True, sign=-1.0, n=n)
    held: dict[str, np.ndarray] | None = None
    g0 = 0
    for b in _batches(path, names):
        tab: Mapping[str, np.ndarray] = b if held is None else \
            {c: np.concatenate([held[c], b[c]]) for c in names}
        v_w, v_b = _columns(tab, "plant/state/v_w"), _columns(tab, "plant/state/v_b")
        v_rel = v_w - v_b
        keep = g0 + len(v_w)
        if "damper" in bonds:
            keep = min(keep, bonds["damper"].add(
                g0, _columns(tab, "controller/force/F_d"), _columns(tab, "controller/force/c_eff"),
                v_rel, v_rel))
        if "tyre" in bonds:
            keep = min(keep, bonds["tyre"].add(
                g0, _columns(tab, "tyre_road/force/F_t"), _columns(tab, "tyre_road/force/k_t"),
                _columns(tab, "plant/state/z_w"), v_w))
        keep = max(g0, keep)
        held = {c: np.asarray(tab[c][keep - g0:]) for c in names}
        g0 = keep
    if not bonds:
        return {}
    out = {name: bd.relative for name, bd in bonds.items()}
    carried = sum(bd.carried for bd in bonds.values())
    out["total"] = (sum(bd.abs_residual for bd in bonds.values()) / carried
                    if carried > 0 else 0.0)
    return out
