"""#29 item 1: the run's report shows the coupling energy residual (total and per bond) and
says so when it is above the threshold the printout warns at."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

from cosim.coupling_energy import WARNING_THRESHOLD
from orchestrator.report.run_page import coupling_residual_rows, run_header


def _run(res: dict | None) -> SimpleNamespace:
    summary = {"status": "ok", "wall_s": 1.0}
    if res is not None:
        summary["coupling_energy_residual"] = res
    return SimpleNamespace(summary=summary, run_id="r1", status="ok", path=Path("."),
                           problems=[], scenario=None, fatigue=None)


def test_the_residual_is_shown_per_bond_and_warned_about_above_the_threshold() -> None:
    res = {"damper": 0.00588, "tyre": 0.00141, "total": 0.00286}
    assert coupling_residual_rows({"coupling_energy_residual": res}) == [
        ("coupling energy residual [%]", 100 * 0.00286), ("  damper bond [%]", 100 * 0.00588),
        ("  tyre bond [%]", 100 * 0.00141)]
    quiet = run_header(_run(res))
    assert "coupling energy residual [%]" in quiet and "damper bond" in quiet
    assert "is above" not in quiet  # 0.286 % < 0.3 %
    loud = run_header(_run({**res, "total": 2 * WARNING_THRESHOLD}))
    assert "is above 0.3 %" in loud
    assert coupling_residual_rows({}) == []
    assert "coupling energy residual" not in run_header(_run(None))
