"""#29 item 1: the live coupling residual on the bus, tapped from a real distributed run.

The Chapter 3 quarter car with held forces in the parallel exchange (a residual of a few %,
both ends of every step counting), its nodes in their own processes over Zenoh on loopback.
A session of the test's own (what ``suscosim tap`` is) subscribes to ``recorder/coupling``;
after the run, the messages it heard must give every step's ``dE`` of both bonds bit for bit
as the finished run's ``table.parquet`` does, and their last running totals the run's
``summary.json``. A ``suscosim scope`` on the same run serves the same running residual on
``/data`` (one point per message), and replays it from the finished run's journal.
"""

from __future__ import annotations

import json
import threading
import time

import numpy as np
import pytest

from cosim import channels as ch
from cosim import coupling_energy as ce
from cosim import keys
from cosim.bus import free_loopback_endpoint
from cosim.table import read_table
from cosim.wire import decode

from .. import coupling_oracle as oracle
from ..conftest import CH3_STEP, popen_suscosim, run_client
from .test_scope import _start_scope, _stop, _until, _wait_json

pytestmark = pytest.mark.integration

RUN_ID = "coupling-live"
T_END = 2.0  # s: 2000 steps, about twenty messages


N_LAST = 2000 - 2  # the last step with a residual (parallel exchange: n - 1 - lag)


@pytest.fixture(scope="module")
def tapped(tmp_path_factory) -> dict:
    """The run, tapped from before its start and watched by a scope."""
    endpoint = free_loopback_endpoint()
    out = tmp_path_factory.mktemp("coupling") / "run"
    heard: list[bytes] = []
    lock = threading.Lock()

    def on(_key: str, raw: bytes) -> None:
        with lock:
            heard.append(raw)

    # the scope first, by run id at the endpoint, before the run (it waits for the run to
    # listen): started on the run folder once run.json was there, it joined a loaded CI
    # machine's 2 s run after its end and never heard a message (both tests errored in the
    # fixture). The test's own session is a client of the run's orchestrator (a tap's way in),
    # which can only open once the run listens: it subscribes then, while the nodes start.
    bus = proc = scope = None
    seen: dict = {"out": out}
    try:
        scope, url = _start_scope(RUN_ID, "--connect", endpoint)
        proc = popen_suscosim("run", str(CH3_STEP), "--out", str(out), "--quiet", "--listen",
                              endpoint, "--set", f"run.t_end={T_END}", "--set",
                              f'run.id="{RUN_ID}"', "--set", 'run.coupling="hold"', "--set",
                              'run.exchange="parallel"')
        bus = run_client(endpoint)
        bus.subscribe(keys.key(RUN_ID, *ch.COUPLING_CHANNEL), on)
        assert bus.wait_linked(60), "the test's session never reached the run"
        _wait_json(out / "run.json", proc)
        stdout, stderr = proc.communicate(timeout=240)
        assert proc.returncode == 0, stdout + stderr
        deadline = time.monotonic() + 5
        while time.monotonic() < deadline:  # the last message is sent before 'done'
            with lock:
                if heard and decode(heard[-1]).k == N_LAST:
                    break
            time.sleep(0.05)
        seen["scope"] = _until(url, lambda d: (d["coupling"] or {}).get("last", {})
                               .get("k") == N_LAST, timeout=60)
        _stop(scope)
        replay, url = _start_scope(str(out), "--fast")
        seen["replay"] = _until(url, lambda d: d["run_state"] == "done" and (
            d["coupling"] or {}).get("last", {}).get("k") == N_LAST, timeout=120)
        _stop(replay)
    finally:
        if bus is not None:
            bus.close()
        for p in (proc, scope):
            if p is not None and p.poll() is None:
                p.kill()
    seen["messages"] = [decode(raw) for raw in heard]
    return seen


def test_the_tapped_residual_is_the_tables_step_by_step(tapped) -> None:
    out, msgs = tapped["out"], tapped["messages"]
    data = [m for m in msgs if m.kind == "data"]
    assert len(data) >= 2, [m.kind for m in msgs]
    # the steps the messages give: k0 .. k, one after another, 1 .. n - 2 (parallel: lag 1)
    k_next = 1
    series: dict[str, list[float]] = {"damper": [], "tyre": []}
    for m in data:
        n = len(m.d["dE_damper"])
        assert m.d["k0"] == k_next and m.k == k_next + n - 1, (m.d["k0"], m.k, k_next)
        assert m.t == pytest.approx(m.k * 1e-3, abs=1e-9)
        k_next += n
        for bond in series:
            series[bond] += m.d[f"dE_{bond}"]
    assert k_next - 1 == N_LAST
    table = read_table(out / "table.parquet")
    ref = oracle.coupling_residual(table, 1e-3, "hold", "parallel")
    assert set(ref) == {"damper", "tyre"}
    for bond, r in ref.items():
        assert np.array_equal(np.asarray(series[bond]), r.dE), bond  # bit for bit
    summary = json.loads((out / "summary.json").read_text())
    res = summary["coupling_energy_residual"]
    last = data[-1].d
    for name in ("damper", "tyre", "total"):  # the same sums, taken in other blocks
        assert last[f"rel_{name}"] == pytest.approx(res[name], rel=1e-12), name
    assert last["rel_total"] > last["threshold"] == ce.WARNING_THRESHOLD
    assert not any(c.startswith("recorder/") for c in table)  # the channel is not in it


def test_the_scope_serves_the_tapped_residual(tapped) -> None:
    data = [m for m in tapped["messages"] if m.kind == "data"]
    c = tapped["scope"]["coupling"]
    # one point per message, every message from the scope's first on (a scope started on a
    # loaded machine may join after the recorder's first messages)
    ks = [m.k for m in data]
    heard = data[ks.index(c["k"][0]):]
    assert c["k"] == [m.k for m in heard]
    for bond in ("damper", "tyre", "total"):
        assert c["rel"][bond] == [m.d[f"rel_{bond}"] for m in heard], bond
    assert c["threshold"] == ce.WARNING_THRESHOLD
    assert c["steps"] == sum(len(m.d["dE_damper"]) for m in heard)
    # the replay computes it again from the journal: the same end
    r = tapped["replay"]["coupling"]
    assert r["steps"] == N_LAST and r["from_k"] == 1
    for f in ("rel_damper", "rel_tyre", "rel_total", "res_tyre", "carried_damper"):
        assert r["last"][f] == pytest.approx(data[-1].d[f], rel=1e-12), f
