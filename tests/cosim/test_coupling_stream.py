"""#29 item 1 / #32: the coupling residual computed block by block (a live node's steps, a
long run's row groups) equals the whole-table computation, per step bit for bit, with a
bounded number of rows held."""

from __future__ import annotations

import tracemalloc
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from cosim import coupling_energy as ce
from cosim.coupling_stream import ResidualStream, residual_of_table_file, summary_of_table_file
from cosim.table import write_parquet

from .. import coupling_oracle as oracle


def _table(n: int, corners: int, seed: int = 0) -> dict[str, np.ndarray]:
    """A synthetic run: smooth states, forces that follow them with noise (a coupling error)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 1e-3
    out: dict[str, np.ndarray] = {"k": np.arange(n, dtype=np.int64), "t": t}

    def col(name: str, a: np.ndarray) -> None:
        if corners == 1:
            out[name] = a[:, 0]
        else:
            for i in range(corners):
                out[f"{name}[{i}]"] = a[:, i]

    ph = rng.uniform(0, 6, corners)
    v_w = np.cos(2 * np.pi * 9 * t[:, None] + ph)
    v_b = 0.2 * np.cos(2 * np.pi * 1.2 * t[:, None] + ph)
    z_w = np.sin(2 * np.pi * 9 * t[:, None] + ph) / (2 * np.pi * 9)
    col("plant/state/v_w", v_w)
    col("plant/state/v_b", v_b)
    col("plant/state/z_w", z_w)
    col("controller/force/F_d", 1500 * (v_w - v_b) + rng.normal(0, 5, (n, corners)))
    col("controller/force/c_eff", np.full((n, corners), 1500.0))
    col("tyre_road/force/F_t", np.maximum(0, 4000 - 2e5 * z_w + rng.normal(0, 20, (n, corners))))
    col("tyre_road/force/k_t", np.full((n, corners), 2e5))
    return out


@pytest.mark.parametrize("coupling", ["hold", "linear", "jacobian"])
@pytest.mark.parametrize("exchange", ["sequential", "parallel"])
@pytest.mark.parametrize("corners", [1, 4])
def test_blocks_of_any_size_give_the_whole_table_residual(coupling, exchange, corners) -> None:
    table = _table(997, corners)
    ref = oracle.coupling_residual(table, 1e-3, coupling, exchange)
    assert set(ref) == {"damper", "tyre"}
    stream = ResidualStream(1e-3, coupling, exchange)
    rng = np.random.default_rng(3)
    series: dict[str, list[np.ndarray]] = {}
    i = 0
    while i < 997:
        m = int(rng.choice([1, 2, 3, 50, 211]))
        for bond, dE in stream.feed({c: a[i:i + m] for c, a in table.items()}).items():
            series.setdefault(bond, []).append(dE)
        i += m
        for st in (stream.bonds or {}).values():  # bounded: a few rows kept, whatever the run
            assert len(st.tail["F"]) <= 4
    got = stream.result()
    for bond, r in ref.items():
        np.testing.assert_array_equal(np.concatenate(series[bond]), r.dE)  # step by step
        assert got[bond].abs_residual == pytest.approx(r.abs_residual, rel=1e-12)
        assert got[bond].carried == pytest.approx(r.carried, rel=1e-12)
    assert ce.summary(got)["total"] == pytest.approx(ce.summary(ref)["total"], rel=1e-12)


def test_a_table_file_read_in_row_groups_gives_the_whole_table_residual(tmp_path: Path) -> None:
    table = _table(5000, 1, seed=7)
    table["plant/response/a_b"] = np.zeros(5000)  # a column the residual does not read
    write_parquet(table, tmp_path / "table.parquet")
    ref = oracle.coupling_residual(table, 1e-3, "hold", "parallel")
    got = residual_of_table_file(str(tmp_path / "table.parquet"), 1e-3, "hold", "parallel",
                                 batch_rows=333)
    for bond, r in ref.items():
        assert got[bond].abs_residual == pytest.approx(r.abs_residual, rel=1e-12)


def test_a_run_without_a_bond_leaves_it_out_and_bad_settings_are_refused() -> None:
    table = {c: a for c, a in _table(50, 1).items() if not c.startswith("controller/")}
    stream = ResidualStream(1e-3, "hold", "sequential")
    assert set(stream.feed(table)) == {"tyre"}
    with pytest.raises(ValueError, match="communication step"):
        ResidualStream(0.0, "hold", "sequential")
    with pytest.raises(ValueError, match="unknown coupling"):
        ResidualStream(1e-3, "spline", "sequential")


def _write_groups(path: Path, table: dict[str, np.ndarray], group: int = 1000) -> None:
    """A table.parquet as the recorder writes it: row groups as the run goes."""
    w = pq.ParquetWriter(path, pa.table({c: v[:1] for c, v in table.items()}).schema)
    for i in range(0, len(table["t"]), group):
        w.write_table(pa.table({c: v[i:i + group] for c, v in table.items()}))
    w.close()


def test_the_summary_of_a_table_file_holds_no_more_memory_for_a_longer_run(tmp_path) -> None:
    """#32: the orchestrator's summary read the bonds' columns whole (223 -> 471 MB peak RSS
    from 10^5 to 10^6 steps); by row groups its peak does not grow with the run."""
    peaks, sums = [], []
    for n in (20_000, 100_000):
        table = _table(n, 4, seed=n)
        _write_groups(tmp_path / f"t{n}.parquet", table)
        tracemalloc.start()
        got = summary_of_table_file(tmp_path / f"t{n}.parquet", 1e-3, "jacobian", "parallel")
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
        whole = oracle.coupling_residual(table, 1e-3, "jacobian", "parallel")
        sums.append((got, ce.summary(whole)))
    assert peaks[1] < 1.2 * peaks[0], peaks
    for got, whole in sums:
        assert set(got) == set(whole) == {"damper", "tyre", "total"}
        for k, v in whole.items():
            assert got[k] == pytest.approx(v, rel=1e-12), k
    table = {c: a for c, a in _table(100, 1).items() if not c.startswith(("controller/",
                                                                            "tyre_road/"))}
    _write_groups(tmp_path / "none.parquet", table)
    assert summary_of_table_file(tmp_path / "none.parquet", 1e-3, "hold", "sequential") == {}
