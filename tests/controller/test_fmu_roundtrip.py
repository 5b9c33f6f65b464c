"""Round trip through FMI in a real co-simulation: the TSS1 law of the Chapter 5 scenario
exported with ``suscosim export-fmu``, then run by the controller node as ``law = "fmu"``
(FMPy in the node's process, real Zenoh between real node processes), gives the same body
and wheel responses as the native law.

Tolerance: 1e-9 relative (the issue's); the doubles cross the FMI C interface unchanged and
the FMU evaluates the same Python arithmetic, so the runs are in fact bit-identical (asserted
too: a difference would mean the FMU path changes the numbers)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from cosim.table import read_table

from ..conftest import ROOT, suscosim

pytestmark = pytest.mark.integration

TSS1 = ROOT / "scenarios" / "ch5_qvm_tss1_random.toml"
RESPONSES = ("plant/state/z_b", "plant/state/v_b", "plant/state/z_w", "plant/state/v_w",
             "plant/response/a_b", "plant/response/a_w", "controller/force/F_d",
             "controller/force/c_eff", "controller/force/state", "tyre_road/force/F_t")


def test_exported_tss1_fmu_reproduces_the_native_run(tmp_path: Path) -> None:
    fmu = tmp_path / "tss1.fmu"
    res = suscosim("export-fmu", str(TSS1), "--out", str(fmu))
    assert res.returncode == 0, res.stderr + res.stdout
    text = TSS1.read_text()
    scenario = tmp_path / "ch5_qvm_tss1_fmu.toml"
    scenario.write_text(text[: text.index("\n[controller]") + 1]
                        + f'[controller]\nlaw = "fmu"\nfmu = "{fmu}"\n')
    tables = {}
    for name, path in (("native", TSS1), ("fmu", scenario)):
        out = tmp_path / name
        res = suscosim("run", str(path), "--out", str(out), "--quiet", "--set", "run.t_end=1.0",
                       timeout=180.0)
        assert res.returncode == 0, res.stderr + res.stdout
        summary = json.loads((out / "summary.json").read_text())
        assert summary["status"] == "ok" and summary["mode"] == "distributed"
        assert summary["n_steps"] == 500
        tables[name] = read_table(out / "table.parquet")
    native, via_fmu = tables["native"], tables["fmu"]
    state = np.asarray(native["controller/force/state"], dtype=float)
    assert 0 < state.sum() < state.size, "TSS1 switches on this road: the test means something"
    for channel in RESPONSES:
        a = np.asarray(native[channel], dtype=float)
        b = np.asarray(via_fmu[channel], dtype=float)
        assert a.shape == b.shape == (501,), channel
        scale = float(np.max(np.abs(a)))
        assert float(np.max(np.abs(a - b))) <= 1e-9 * scale, channel
        np.testing.assert_array_equal(a, b, err_msg=channel)
