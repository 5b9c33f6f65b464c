"""#29 item 1: the live ``recorder/coupling`` messages, built from the rows as a table writes
them, carry each step's residual bit for bit as the whole table's, and the running totals of
:class:`ResidualStream`."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cosim import coupling_energy as ce
from cosim.coupling_stream import MAX_STEPS, LiveResidual, ResidualStream
from cosim.table import read_table
from cosim.table_writer import TableWriter
from cosim.wire import MAX_MESSAGE_BYTES, decode, encode

from .. import coupling_oracle as oracle
from .test_coupling_stream import _table

CHANNELS = {"plant/state": ("v_b", "z_w", "v_w"),
            "controller/force": ("F_d", "c_eff"), "tyre_road/force": ("F_t", "k_t")}


def _messages(table: dict[str, np.ndarray], corners: int) -> list[tuple[str, int, dict]]:
    """The run's data messages, step by step, the channels of a step in a shuffled order and
    a channel sometimes a step ahead (as records batches of three producers interleave)."""
    n = len(table["k"])
    rng = np.random.default_rng(11)

    def value(chan: str, fld: str, k: int) -> float | list[float]:
        name = f"{chan}/{fld}"
        if corners == 1:
            return float(table[name][k])
        return [float(table[f"{name}[{i}]"][k]) for i in range(corners)]

    out = []
    ahead: list[tuple[str, int, dict]] = []
    for k in range(n):
        step = [(c, k, {f: value(c, f, k) for f in fs}) for c, fs in CHANNELS.items()]
        rng.shuffle(step)
        out += ahead
        ahead = []
        if rng.random() < 0.3:  # one channel's message of step k after another's of k + 1
            ahead, step = step[:1], step[1:]
        out += step
    return out + ahead


def _feed(msgs, live: LiveResidual, table: TableWriter, every: int):
    """Feed as the recorder does; take the live messages every ``every`` data messages."""
    got = []
    for i, (chan, k, d) in enumerate(msgs):
        rows = table.rows
        assert table.add(chan, k, k * 1e-3, d) is None
        live.add(chan, k, k * 1e-3, d)
        if table.rows > rows:
            live.row(k)
        if i % every == every - 1:
            got += live.take()
    return got + live.take()


@pytest.mark.parametrize("exchange", ["sequential", "parallel"])
@pytest.mark.parametrize("corners", [1, 4])
@pytest.mark.parametrize("every", [1, 7, 5000])
def test_messages_carry_the_whole_table_residual_step_by_step(exchange, corners, every) -> None:
    n = 3100 if every == 5000 else 997  # 5000: one take of 3 x MAX_STEPS rows and more
    ref_table = _table(n, corners)
    ref = oracle.coupling_residual(ref_table, 1e-3, "linear", exchange)
    live = LiveResidual(1e-3, "linear", exchange, CHANNELS)
    writer = TableWriter(CHANNELS, None)
    got = _feed(_messages(ref_table, corners), live, writer, every)
    assert writer.rows == n and got
    lag = 0 if exchange == "sequential" else 1
    k_next = lag
    series: dict[str, list[float]] = {"damper": [], "tyre": []}
    stream = ResidualStream(1e-3, "linear", exchange)
    for k, t, d in got:
        raw = encode("data", k, t, d)
        assert len(raw) <= MAX_MESSAGE_BYTES
        back = decode(raw, "recorder/coupling").d  # as a tap reads it: the same numbers
        assert back == d
        m = len(d["dE_damper"])
        assert d["k0"] == k_next and k == k_next + m - 1 and 1 <= m <= MAX_STEPS
        assert t == pytest.approx(k * 1e-3, abs=0)
        k_next += m
        for bond in series:
            series[bond] += d[f"dE_{bond}"]
        assert d["threshold"] == ce.WARNING_THRESHOLD
        assert d["rel_total"] == pytest.approx(
            (d["res_damper"] + d["res_tyre"]) / (d["carried_damper"] + d["carried_tyre"]),
            rel=1e-15)
    assert k_next == n - 1 - lag  # steps lag .. n - 2 - lag, as the whole table
    for bond, r in ref.items():
        assert np.array_equal(np.asarray(series[bond]), r.dE), bond  # bit for bit
    # the last message's running totals are the whole run's (to the order of the sums)
    last = got[-1][2]
    stream.feed(ref_table)
    for bond, r in stream.result().items():
        assert last[f"res_{bond}"] == pytest.approx(r.abs_residual, rel=1e-12)
        assert last[f"carried_{bond}"] == pytest.approx(r.carried, rel=1e-12)
        assert last[f"rel_{bond}"] == pytest.approx(r.relative, rel=1e-12)
    assert last["rel_total"] == pytest.approx(ce.summary(ref)["total"], rel=1e-12)
    assert last["rel_total"] > 0


def test_a_step_the_table_drops_is_dropped_too(tmp_path: Path) -> None:
    """Step 40's controller message comes after step 41's row was written: the table leaves
    step 40 out (``late``), so does the live residual; its messages are then cut at the gap
    and still equal the residual of the table's own rows, read back from table.parquet."""
    ref_table = _table(300, 1, seed=5)
    msgs = _messages(ref_table, 1)
    i = next(j for j, (c, k, _d) in enumerate(msgs) if (c, k) == ("controller/force", 40))
    late = msgs.pop(i)
    j = max(j for j, (_c, k, _d) in enumerate(msgs) if k == 41)
    msgs.insert(j + 1, late)
    live = LiveResidual(1e-3, "hold", "sequential", CHANNELS)
    writer = TableWriter(CHANNELS, tmp_path)
    got = _feed(msgs, live, writer, 1)
    writer.close()
    assert writer.late == 1 and writer.rows == 299
    assert live.held == 0  # step 40's messages are not kept for ever
    table = read_table(tmp_path / "table.parquet")
    assert 40 not in table["k"]
    ref = oracle.coupling_residual(table, 1e-3, "hold", "sequential")
    ks: list[int] = []
    dE: list[float] = []
    for k, _t, d in got:
        n = len(d["dE_damper"])
        assert k == d["k0"] + n - 1
        ks += range(d["k0"], d["k0"] + n)
        dE += d["dE_damper"]
    assert np.array_equal(np.asarray(dE), ref["damper"].dE)
    assert ks == [int(k) for k in table["k"][:-1]]  # the rows' steps but the last


def test_no_bond_no_message() -> None:
    """A table without the bonds' channels (a plant alone) gives no message."""
    live = LiveResidual(1e-3, "hold", "sequential", ["plant/response"])
    for k in range(10):
        live.add("plant/response", k, k * 1e-3, {"a_b": 0.0})
        live.row(k)
    assert live.take() == []


def test_bad_settings_are_refused() -> None:
    with pytest.raises(ValueError, match="must be > 0"):
        LiveResidual(0.0, "hold", "sequential", CHANNELS)
    with pytest.raises(ValueError, match="unknown coupling"):
        LiveResidual(1e-3, "zoh", "sequential", CHANNELS)
