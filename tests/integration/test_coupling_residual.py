"""The coupling residual against the true error on the Chapter 3 quarter car (issue #29).

Real monolithic runs of the node code (the same numbers as distributed) over the 20 mm step:
the residual, computed from the run's table alone, must rank the step sizes as the error
against the reference solution does, and sit within the factor the study in
docs/coupling_residual.md found (true error = 3-4.5 x residual for the held forces).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cosim import coupling_energy as ce
from cosim import scenario as sc
from cosim.table import read_table
from orchestrator.accuracy import peak_errors, worst
from orchestrator.reference import reference_solution
from orchestrator.runner import resolve, run_scenario

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "ch3_step_quarter_car.toml"
T_END = 1.5


def _run(tmp: Path, h: float, coupling: str, exchange: str) -> dict[str, np.ndarray]:
    d = tmp / f"{exchange}-{coupling}-{h}"
    s = resolve(sc.load(SCENARIO, [f"run.h={h}", f'run.coupling="{coupling}"',
                                   f'run.exchange="{exchange}"', 'run.mode="monolithic"',
                                   f"run.t_end={T_END}"]), d)
    run_scenario(s, quiet=True)
    return read_table(d / "table.parquet")


@pytest.mark.parametrize("exchange", ["sequential", "parallel"])
def test_residual_ranks_step_sizes_as_the_true_error(tmp_path: Path, exchange: str) -> None:
    ref = reference_solution(resolve(sc.load(SCENARIO, [f"run.t_end={T_END}"]), tmp_path / "r"),
                             np.arange(0, T_END + 1e-9, 2e-5))
    true, residual = [], []
    for h in (0.001, 0.002, 0.004):
        table = _run(tmp_path, h, "hold", exchange)
        true.append(worst(peak_errors(table, ref, t_from=0.4)))
        residual.append(ce.summary(ce.coupling_residual(table, h, "hold", exchange))["total"])
    assert np.all(np.diff(true) > 0) and np.all(np.diff(residual) > 0)
    ratio = np.asarray(true) / (100 * np.asarray(residual))
    assert np.all((ratio > 1.5) & (ratio < 6)), ratio


def test_exact_linearisation_leaves_no_coupling_residual(tmp_path: Path) -> None:
    # the linear tyre and damper are linearised exactly by the jacobian coupling: what error
    # is left is the plant's own integration (the same in both exchange orders)
    table = _run(tmp_path, 0.002, "jacobian", "sequential")
    res = ce.coupling_residual(table, 0.002, "jacobian", "sequential")
    assert set(res) == {"damper", "tyre"}
    assert res["damper"].carried > 0 and res["tyre"].carried > 0
    assert ce.summary(res)["total"] < 1e-9
