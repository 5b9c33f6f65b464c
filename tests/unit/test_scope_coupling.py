"""#29 item 1: the scope serves the coupling residual (``recorder/coupling``).

* Live: messages on the bus (an in-memory bus, as the scope's Zenoh subscribers see them)
  reach ``/data`` over HTTP: one point per message, the running relative residual of each
  bond and the total, the threshold, the last totals; ``coupling_since`` gives only the
  points after it; a bad ``coupling_since`` is a 400.
* Replay: a finished run's journal holds no ``recorder/coupling``; the replay computes it
  again from the journaled messages, the same numbers as the live messages.
"""

from __future__ import annotations

import json
import time
import urllib.error
import urllib.request
from typing import Any

import numpy as np
import pytest

from cosim import channels as ch
from cosim import coupling_energy as ce
from cosim import keys
from cosim.coupling_stream import LiveResidual
from cosim.table_writer import TableWriter
from cosim.wire import encode
from orchestrator.scope.server import ScopeServer
from orchestrator.scope.sources import JournalSource, LiveSource
from orchestrator.scope.state import ScopeState, Selection
from tests.memory_bus import MemoryBus

from ..cosim.test_coupling_live import CHANNELS, _messages
from ..cosim.test_coupling_stream import _table

RUN: dict[str, Any] = {"h": 1e-3, "coupling": "hold", "exchange": "parallel",
                       "mode": "distributed"}


def _recorded(n: int = 2500):
    """The data messages of a synthetic run in the recorder's order, and the
    ``recorder/coupling`` messages the recorder builds from them (taken every 300)."""
    msgs = _messages(_table(n, 1, seed=2), 1)
    live = LiveResidual(RUN["h"], RUN["coupling"], RUN["exchange"], CHANNELS)
    table = TableWriter(CHANNELS, None)
    out = []
    for i, (chan, k, d) in enumerate(msgs):
        rows = table.rows
        table.add(chan, k, k * 1e-3, d)
        live.add(chan, k, k * 1e-3, d)
        if table.rows > rows:
            live.row(k)
        if i % 300 == 299:
            out += live.take()
    return msgs, out + live.take()


def _get(url: str) -> dict:
    with urllib.request.urlopen(url, timeout=10) as r:
        return json.loads(r.read())


def _until(state: ScopeState, ok, timeout: float = 20.0) -> dict:
    deadline = time.monotonic() + timeout
    while True:
        d = state.snapshot()
        if ok(d):
            return d
        assert time.monotonic() < deadline, d["coupling"]
        time.sleep(0.02)


def test_live_residual_messages_are_served() -> None:
    _msgs, coupling = _recorded()
    assert len(coupling) >= 3
    bus = MemoryBus()
    state = ScopeState("cpl", Selection(["plant/state/z_w"]))
    source = LiveSource(bus, state)
    assert keys.key("cpl", *ch.COUPLING_CHANNEL) in source.keyexprs()
    source.start()
    server = ScopeServer(state)
    server.start()
    try:
        pub = bus.publisher(keys.key("cpl", *ch.COUPLING_CHANNEL))
        for k, t, d in coupling:
            pub(encode("data", k, t, d))
        last_k = coupling[-1][0]
        _until(state, lambda d: (d["coupling"] or {}).get("k", [None])[-1:] == [last_k])
        every = _get(f"{server.url}data")
        cut = coupling[1][0]
        after = _get(f"{server.url}data?since=-1&coupling_since={cut}")
        with pytest.raises(urllib.error.HTTPError) as bad:
            _get(f"{server.url}data?coupling_since=x")
    finally:
        server.close()
        source.close()
    assert bad.value.code == 400
    c = every["coupling"]
    assert c["k"] == [k for k, _t, _d in coupling]
    assert c["t"] == [t for _k, t, _d in coupling]
    for bond in ("damper", "tyre", "total"):
        assert c["rel"][bond] == [d[f"rel_{bond}"] for _k, _t, d in coupling], bond
    assert c["threshold"] == ce.WARNING_THRESHOLD
    assert c["from_k"] == 1  # parallel exchange: the first step with a residual
    assert c["steps"] == sum(len(d["dE_damper"]) for _k, _t, d in coupling)
    assert c["last"]["k"] == last_k
    assert c["last"]["res_tyre"] == coupling[-1][2]["res_tyre"]
    assert after["coupling"]["k"] == [k for k, _t, _d in coupling[2:]]


def test_a_replay_computes_the_live_residual_again() -> None:
    msgs, coupling = _recorded()

    class Journal(list):  # what orchestrator.replay.Recorded gives: records and channels
        channels = {tuple(c.split("/")) for c in CHANNELS}

    records = Journal((c.split("/")[0], c.split("/")[1], encode("data", k, k * 1e-3, d),
                       k * 1e-3) for c, k, d in msgs)
    state = ScopeState("cpl", Selection(["plant/state/z_w"]), source="replay")
    source = JournalSource(records, state, speed=None, run=RUN)
    source.start()
    try:
        d = _until(state, lambda d: d["run_state"] == "done")
    finally:
        source.close()
    c = d["coupling"]
    # other batches than the recorder's (the replay's own pace): the same running values at
    # the steps both have, and the same end
    live = {k: dd for k, _t, dd in coupling}
    both = [i for i, k in enumerate(c["k"]) if k in live]
    assert c["k"][-1] == coupling[-1][0] and c["steps"] == 2500 - 1 - 2 and both
    for bond in ("damper", "tyre", "total"):
        mine = np.asarray([c["rel"][bond][i] for i in both])
        theirs = np.asarray([live[c["k"][i]][f"rel_{bond}"] for i in both])
        np.testing.assert_allclose(mine, theirs, rtol=1e-12)
    assert c["last"]["rel_total"] == pytest.approx(coupling[-1][2]["rel_total"], rel=1e-12)
    assert c["last"]["rel_total"] > 0
