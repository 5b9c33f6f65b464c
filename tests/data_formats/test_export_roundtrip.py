"""#20: a realistic run's arm channels exported to MDF 4 and RPC III, read back by asammdf and
by rpc-reader (an RPC III reader independent of the rpc3-file writer), equal the table (MDF 4
exactly, RPC III within half a count of its stated resolution), and fed to ``suscosim
fatigue`` give the run's own life."""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import numpy as np
import pytest

from cosim.formats import si_unit
from cosim.table import read_table

from .conftest import cli

pytestmark = pytest.mark.integration


def _arm(table: dict) -> list[str]:
    names = [c for c in table if c.startswith("plant/arm/")]
    assert len(names) == 15  # 4 joints x 3 + torsion bar + bump stop y/z
    return names


def _export(run: Path, fmt: str, capsys) -> tuple[Path, dict]:
    rc, out, err = cli(capsys, "export", str(run), "--format", fmt, "--channels", "plant/arm/*")
    assert rc == 0, out + err
    info = json.loads(out)
    return Path(info["files"][fmt]), info


def test_mdf4_read_by_asammdf_equals_the_table_exactly(pave_run: Path, capsys) -> None:
    from asammdf import MDF

    path, info = _export(pave_run, "mdf4", capsys)
    table = read_table(pave_run / "table.parquet")
    names = _arm(table)
    assert info["channels"] == len(names) and info["rows"] == len(table["t"])
    with MDF(str(path)) as mdf:
        for name in names:
            sig = mdf.get(name)
            assert sig.unit == si_unit(name) and sig.unit in ("N", "N m")
            np.testing.assert_array_equal(sig.timestamps, table["t"])
            np.testing.assert_array_equal(sig.samples, table[name])


def test_rpc3_read_by_rpc_reader_equals_the_table_within_its_resolution(pave_run: Path,
                                                                        capsys) -> None:
    from rpc_reader.rpc_reader import ReadRPC

    path, info = _export(pave_run, "rpc3", capsys)
    table = read_table(pave_run / "table.parquet")
    names = _arm(table)
    reader = ReadRPC(path)
    with contextlib.redirect_stdout(io.StringIO()):  # it prints its progress
        reader.import_rpc_data_from_file()
    headers, channels, data = reader.get_headers(), reader.get_channels(), reader.get_data()
    assert headers["DATA_TYPE"] == "SHORT_INTEGER"
    assert headers["DELTA_T"] == pytest.approx(5e-4, rel=1e-12)  # the run's h
    n = len(table["t"])
    assert data.shape[0] >= n  # the last group is padded
    for i, name in enumerate(names):
        assert channels[i]["Description"] == name and channels[i]["Units"] == si_unit(name)
        res = info["resolution"][name]
        x = table[name]
        # stated resolution: one 16-bit count, max|x| / 32752
        assert res == pytest.approx(np.max(np.abs(x)) / 32752, rel=1e-12) or np.all(x == 0)
        err = np.max(np.abs(data[:n, i] - x))
        assert err <= 0.5 * res * (1 + 1e-9), (name, err, res)
        if np.any(x):
            assert err > 0  # really quantised: the test would see a wrong scale


@pytest.mark.parametrize("fmt", ["mdf4", "rpc3", "csv", "parquet"])
def test_exported_loads_give_the_runs_life(pave_run: Path, fmt: str, tmp_path: Path,
                                           capsys) -> None:
    path, _ = _export(pave_run, fmt, capsys)
    rc, out, err = cli(capsys, "fatigue", str(path), "--scenario", str(pave_run), "--out",
                       str(tmp_path))
    assert rc == 0, out + err
    mine = json.loads((tmp_path / "summary.json").read_text())
    base = json.loads((pave_run / "fatigue" / "summary.json").read_text())
    assert mine["missing_channels"] == [] and mine["n_samples"] == base["n_samples"]
    assert mine["critical_node_id"] == base["critical_node_id"]
    assert mine["track_length_m"] == base["track_length_m"] == 100.0
    if fmt == "rpc3":  # loads within 3e-5 of their peaks: the life within 1e-3
        assert mine["min_life_km"] == pytest.approx(base["min_life_km"], rel=1e-3)
        assert mine["min_life_km"] != base["min_life_km"]
    else:  # float64 all the way: the same numbers
        assert mine["min_life_km"] == base["min_life_km"]
        assert mine["max_damage_per_pass"] == base["max_damage_per_pass"]


def test_streamed_exports_equal_the_whole_table_writers(pave_run: Path, tmp_path: Path,
                                                        capsys) -> None:
    """#32: ``export RUN --format csv|parquet`` streamed from table.parquet in batches (here
    of 500 rows, so the 1201 rows take three) writes what the whole-table writers write: the
    CSV byte for byte, the Parquet the same columns, values and units; with --channels the
    file is named by the selection (#30 item 3), so the whole export is not replaced."""
    from cosim.formats import ChannelSet
    from cosim.formats import stream as st
    from cosim.formats.tables import write_csv, write_parquet
    from cosim.table import read_table
    from orchestrator.export import main as export_main

    st.BATCH_ROWS = 500
    try:
        table = read_table(pave_run / "table.parquet")
        names = [c for c in table if c not in ("k", "t")]
        cs = ChannelSet(t=table["t"], channels={c: table[c] for c in names},
                        units={c: si_unit(c) for c in names})
        write_csv(cs, tmp_path / "whole.csv", units_in_header=True)
        write_parquet(cs, tmp_path / "whole.parquet")
        for fmt in ("csv", "parquet"):
            capsys.readouterr()
            assert export_main([str(pave_run), "--format", fmt, "--out", str(tmp_path)]) == 0
            info = json.loads(capsys.readouterr().out)
            assert info["rows"] == len(table["t"]) and info["channels"] == len(names)
        assert (tmp_path / "table.csv").read_bytes() == (tmp_path / "whole.csv").read_bytes()
        import pyarrow.parquet as pq

        a, b = pq.read_table(tmp_path / "table.parquet"), pq.read_table(tmp_path / "whole.parquet")
        assert a.schema.equals(b.schema, check_metadata=True) and a.equals(b)
        assert export_main([str(pave_run), "--format", "rpc3", "--out", str(tmp_path),
                            "--channels", "plant/arm/*"]) == 0
        assert (tmp_path / "table.plant_arm_x.rsp").is_file()
        assert (tmp_path / "table.csv").read_bytes() == (tmp_path / "whole.csv").read_bytes()
    finally:
        st.BATCH_ROWS = 65536
