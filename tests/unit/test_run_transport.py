"""Which Zenoh transport a distributed run's sessions get (orchestrator.run_modes): the local
nodes the run's (universal by default, low-latency with --lowlatency), the orchestrator's own
session universal in every case (its gossip is not written with a blocking send:
docs/cosim.md "A wedged start")."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from orchestrator import run_modes, runner


class _Recorded:
    def __init__(self) -> None:
        self.configs: list[dict[str, Any]] = []
        self.nodes: list[tuple[Any, ...]] = []


@pytest.fixture()
def recorded(monkeypatch: pytest.MonkeyPatch) -> _Recorded:
    rec = _Recorded()

    def zenoh_config(connect: Any, listen: Any, **kw: Any) -> dict[str, Any]:
        rec.configs.append(kw)
        return kw

    class LocalNodes:
        def __init__(self, *args: Any, **kw: Any) -> None:
            rec.nodes.append(args)

        def check(self) -> None:
            return None

    monkeypatch.setattr(run_modes, "zenoh_config", zenoh_config)
    monkeypatch.setattr(run_modes, "ZenohBus", lambda conf: conf)
    monkeypatch.setattr(run_modes, "LocalNodes", LocalNodes)
    return rec


@pytest.mark.parametrize("lowlatency", [True, False])
def test_the_orchestrator_is_universal_and_its_nodes_take_the_runs_transport(
        recorded: _Recorded, tmp_path: Path, lowlatency: bool) -> None:
    run = {"id": "t", "nodes": ["plant", "tyre_road", "controller", "recorder"],
           "stall_timeout_s": 10.0}
    run_modes.distributed(run, tmp_path, None, None, ["tcp/127.0.0.1:7447"], lowlatency,
                          None, "off", b"k" * 32, False)
    assert [c["lowlatency"] for c in recorded.configs] == [False]  # the orchestrator's session
    (args,) = recorded.nodes
    assert args[3] is lowlatency  # LocalNodes(run_id, names, connect, lowlatency, ...)


def test_universal_nodes_are_the_default() -> None:
    assert runner.LOWLATENCY_DEFAULT is False  # low-latency nodes still wedged a start
