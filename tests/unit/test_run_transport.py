"""Which Zenoh transport a distributed run's sessions get (orchestrator.run_modes): the local
nodes the run's (low-latency by default, universal with --no-lowlatency), the orchestrator's
own session universal in every case; without a Zenoh config file the orchestrator and its
local nodes are an explicit mesh with gossip off (docs/cosim.md "A wedged start")."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from orchestrator import run_modes, runner


class _Recorded:
    def __init__(self) -> None:
        self.configs: list[dict[str, Any]] = []
        self.nodes: list[tuple[Any, ...]] = []
        self.meshes: list[Any] = []


@pytest.fixture()
def recorded(monkeypatch: pytest.MonkeyPatch) -> _Recorded:
    rec = _Recorded()

    def zenoh_config(connect: Any, listen: Any, **kw: Any) -> dict[str, Any]:
        rec.configs.append(kw)
        return kw

    class LocalNodes:
        def __init__(self, *args: Any, **kw: Any) -> None:
            rec.nodes.append(args)
            rec.meshes.append(kw.get("mesh"))

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
    recorded.meshes[0].remove()


def test_without_a_config_file_the_run_is_an_explicit_mesh(recorded: _Recorded,
                                                           tmp_path: Path) -> None:
    run = {"id": "t", "nodes": ["plant", "tyre_road", "controller", "recorder"],
           "stall_timeout_s": 10.0}
    run_modes.distributed(run, tmp_path, None, ["recorder"], ["tcp/127.0.0.1:7447"], True,
                          None, "off", b"k" * 32, False)
    (conf,) = recorded.configs
    (mesh,) = recorded.meshes
    try:
        assert conf["gossip"] is False
        assert mesh.names == ["plant", "tyre_road", "controller"]  # not the external recorder
        (args,) = recorded.nodes
        assert args[2] == []  # the nodes reach the orchestrator on its socket, not its port
        assert mesh.folder.is_dir()
    finally:
        mesh.remove()


def test_with_a_config_file_the_peers_find_each_other_by_gossip(recorded: _Recorded,
                                                                tmp_path: Path) -> None:
    run = {"id": "t", "nodes": ["plant", "tyre_road"], "stall_timeout_s": 10.0}
    cfg = tmp_path / "z.json5"
    cfg.write_text("{}")
    run_modes.distributed(run, tmp_path, None, None, ["tcp/127.0.0.1:7447"], True,
                          str(cfg), "off", b"k" * 32, False)
    assert [c["gossip"] for c in recorded.configs] == [True]
    assert recorded.meshes == [None]
    assert recorded.nodes[0][2] == ["tcp/127.0.0.1:7447"]


def test_low_latency_nodes_are_the_default() -> None:
    assert runner.LOWLATENCY_DEFAULT is True  # safe with the explicit mesh


def test_through_a_router_the_orchestrator_keeps_gossip_its_nodes_a_mesh(
        recorded: _Recorded, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """With --connect (a shared router) the orchestrator gossips, so that the orchestrator
    of a second run with the same id finds it; its nodes are still the explicit mesh, and
    connect to the router too (for the nodes elsewhere, the router's clients)."""
    monkeypatch.setattr(run_modes, "check_run_id_free", lambda *a, **kw: None)
    run = {"id": "t", "nodes": ["plant", "tyre_road"], "stall_timeout_s": 10.0}
    run_modes.distributed(run, tmp_path, ["tcp/127.0.0.1:7000"], None,
                          ["tcp/127.0.0.1:7447"], True, None, "off", b"k" * 32, False)
    assert [c["gossip"] for c in recorded.configs] == [True]
    (mesh,) = recorded.meshes
    try:
        assert mesh.names == ["plant", "tyre_road"]
        assert recorded.nodes[0][2] == ["tcp/127.0.0.1:7000"]
    finally:
        mesh.remove()


@pytest.mark.parametrize(("config_file", "asked", "expected"), [
    (False, None, True), (True, None, False), (True, True, True), (False, False, False)])
def test_a_config_files_run_has_universal_nodes_unless_asked(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path, config_file: bool,
        asked: bool | None, expected: bool) -> None:
    """With --zenoh-config the peers find each other by gossip, where low-latency nodes can
    wedge a start: universal there unless --lowlatency is given (run.json says which)."""
    import json

    from cosim import scenario as sc
    from orchestrator.runner import resolve

    class Stop(Exception):
        pass

    got: list[bool] = []

    def distributed(run: Any, folder: Any, connect: Any, external: Any, listen: Any,
                    lowlatency: bool, *rest: Any) -> None:
        got.append(lowlatency)
        raise Stop

    monkeypatch.setattr(run_modes, "distributed", distributed)
    root = Path(__file__).resolve().parents[2]
    resolved = resolve(sc.load(root / "scenarios" / "ch3_step_quarter_car.toml",
                               ["run.t_end=0.1"]), tmp_path / "run")
    cfg = tmp_path / "z.json5"
    cfg.write_text("{}")
    with pytest.raises(Stop):
        runner.run_scenario(resolved, quiet=True, lowlatency=asked,
                            zenoh_config_file=str(cfg) if config_file else None)
    assert got == [expected]
    assert json.loads((tmp_path / "run" / "run.json").read_text())["lowlatency"] is expected
