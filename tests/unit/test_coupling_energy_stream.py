"""The coupling energy residual from row batches (#32) equals the whole-table one."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from cosim import coupling_energy as ce
from cosim import coupling_energy_stream as ces
from cosim import table_batches


def _write(tmp_path, n: int, corners: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    cols: dict[str, np.ndarray] = {"t": np.arange(n) * 1e-3}

    def put(name: str, x: np.ndarray) -> None:
        if corners == 1:
            cols[name] = x[:, 0]
        else:
            for i in range(corners):
                cols[f"{name}[{i}]"] = x[:, i]

    walk = lambda s: np.cumsum(rng.normal(size=(n, corners)), axis=0) * s  # noqa: E731
    put("plant/state/v_w", walk(1e-2))
    put("plant/state/v_b", walk(1e-3))
    put("plant/state/z_w", walk(1e-4))
    put("controller/force/F_d", walk(10.0))
    put("controller/force/c_eff", 1500 + rng.normal(size=(n, corners)))
    put("tyre_road/force/F_t", np.abs(4000 + walk(30.0)))
    put("tyre_road/force/k_t", 2e5 + rng.normal(size=(n, corners)))
    p = tmp_path / f"t{n}-{corners}.parquet"
    w = pq.ParquetWriter(p, pa.table({c: v[:1] for c, v in cols.items()}).schema)
    for i in range(0, n, 1000):
        w.write_table(pa.table({c: v[i:i + 1000] for c, v in cols.items()}))
    w.close()
    return p, cols


@pytest.mark.parametrize("exchange", ["sequential", "parallel"])
@pytest.mark.parametrize("coupling", ["hold", "linear", "jacobian"])
@pytest.mark.parametrize("corners,rows", [(1, 333), (4, 1000), (4, 7)])
def test_streamed_equals_whole(tmp_path, monkeypatch, exchange, coupling, corners, rows):
    p, cols = _write(tmp_path, 5003, corners)
    monkeypatch.setattr(ces, "_batches",
                        lambda path, names: table_batches.parquet_batches(path, names, rows))
    whole = ce.summary(ce.coupling_residual(cols, 1e-3, coupling, exchange))
    got = ces.coupling_summary(p, 1e-3, coupling, exchange)
    assert set(got) == set(whole)
    for k, v in whole.items():
        assert got[k] == pytest.approx(v, rel=1e-12, abs=0), k


def test_memory_does_not_grow(tmp_path):
    peaks = []
    for n in (20_000, 100_000):
        p, _ = _write(tmp_path, n, 4)
        tracemalloc.start()
        ces.coupling_summary(p, 1e-3, "jacobian", "parallel")
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
    assert peaks[1] < 1.2 * peaks[0], peaks
