"""Test oracle: the whole-history batch outputs (the product computes them streamed,
:func:`nodes.fatigue.run_stream.outputs_streamed`); kept to check the streamed passes."""

from __future__ import annotations

import csv
from collections.abc import Callable
from pathlib import Path

import numpy as np

from nodes.fatigue.config import FatigueConfig
from nodes.fatigue.lib.counting import count_series
from nodes.fatigue.lib.equivalent_stress import equivalent
from nodes.fatigue.lib.influence_set import short_channel
from nodes.fatigue.lib.pseudo_damage import (
    K_REF,
    channel_pseudo_damage,
    matrix_rows,
    rainflow_matrix,
)
from nodes.fatigue.lib.superposition import stress_history
from nodes.fatigue.outputs import (
    SnSpectrum,
    method_table,
    methods_summary,
    sn_plot,
    write_pseudo_damage,
    write_vtu,
)
from nodes.fatigue.worker import FatigueResult, analyse, load_influence


def method_lives(t: np.ndarray, loads: dict, cfg: FatigueConfig, L: float,
                 primary: FatigueResult, say: Callable[[str], None]) -> dict | None:
    """``sn_methods`` (:func:`methods_summary`) of a whole history; the primary's own entry
    is ``primary``."""
    table, left = method_table(cfg)
    if not table:
        return None
    rows = []
    for m, P, c in table:
        if c != cfg:
            say(f"fatigue: S-N method {m} at P = {P:g}")
        rows.append((m, P, c, primary if c == cfg else analyse(t, loads, c, L)))
    return methods_summary(rows, left)


def _case_matrix(loads: dict, cases: list[str], n: int) -> np.ndarray:
    F = np.zeros((n, len(cases)))
    by_short = {short_channel(k): np.asarray(v, dtype=float) for k, v in loads.items()}
    for j, c in enumerate(cases):
        if c in by_short:
            F[:, j] = by_short[c]
    return F


def critical_history(t: np.ndarray, loads: dict, cfg: FatigueConfig,
                     result: FatigueResult) -> tuple[np.ndarray, np.ndarray]:
    """(stress (n, 6) Pa, equivalent stress (n,) Pa) at the critical node."""
    inf = load_influence(cfg)
    c = result.critical_node
    F = _case_matrix(loads, list(inf.case_names), len(t))
    s = stress_history(F, inf.coefficients[:, c:c + 1, :])
    return s[:, 0, :], equivalent(s, cfg.equivalent)[:, 0]


def batch_outputs(t: np.ndarray, loads: dict, cfg: FatigueConfig, L: float,
                  result: FatigueResult, say: Callable[[str], None]
                  ) -> tuple[Callable[[Path], None], dict]:
    """(a writer of the output files into a folder, the summary keys) for one analysis."""
    methods = method_lives(t, loads, cfg, L, result, say)
    say("fatigue: critical-node history, rainflow matrices, pseudo-damage")
    s6, eq = critical_history(t, loads, cfg, result)
    pd = channel_pseudo_damage(loads, K_REF, cfg.residue)
    extra = {"sn_methods": methods,
             "pseudo_damage": {"k": K_REF, "channels": [p.as_dict() for p in pd]},
             "outputs": ["critical_stress.csv", "rainflow_matrix.csv", "pseudo_damage.csv",
                         "sn_plot.png", "sn_plot.json", "damage.vtu"]}

    def write(folder: Path) -> None:
        with open(folder / "critical_stress.csv", "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["t_s", "sxx_pa", "syy_pa", "szz_pa", "sxy_pa", "syz_pa", "szx_pa",
                        f"eq_{cfg.equivalent}_pa"])
            for i in range(len(t)):
                w.writerow([f"{t[i]:.9g}", *(f"{v:.6e}" for v in s6[i]), f"{eq[i]:.6e}"])
        with open(folder / "rainflow_matrix.csv", "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["series", "unit", "range_lo", "range_hi", "mean_lo", "mean_hi",
                        "cycles"])
            cyc = count_series(eq, cfg.residue)
            w.writerows(matrix_rows(f"node_{result.critical_node_id}", "Pa",
                                    rainflow_matrix(cyc)))
            for name, v in loads.items():
                unit = "N m" if short_channel(name).endswith("_mx") else "N"
                w.writerows(matrix_rows(name, unit, rainflow_matrix(
                    count_series(np.asarray(v, dtype=float), cfg.residue))))
        write_pseudo_damage(folder / "pseudo_damage.csv", pd)
        spectrum = SnSpectrum(cfg)
        spectrum.add(cyc)
        sn_plot(folder / "sn_plot.png", cfg, spectrum, result, methods)
        write_vtu(folder / "damage.vtu", result)

    return write, extra
