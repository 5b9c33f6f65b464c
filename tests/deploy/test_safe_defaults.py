"""Safe transport defaults: the embedded session listens on loopback only, no multicast; a
configuration file's choices are kept; nodes started alone are clients of what they join."""

from __future__ import annotations

import json
import os
from pathlib import Path

from cosim.bus import (
    CLIENT_CONNECT_TIMEOUT_MS,
    LOOPBACK_LISTEN,
    ZenohBus,
    free_loopback_endpoint,
    zenoh_config,
)
from orchestrator import node_main


def _own_sockets() -> dict[str, set[tuple[str, str]]]:
    """This process's TCP listening and UDP sockets: {'tcp'|'udp': {(local_ip_hex, port)}}."""
    inodes = set()
    for fd in Path("/proc/self/fd").iterdir():
        try:
            target = os.readlink(fd)
        except OSError:
            continue
        if target.startswith("socket:["):
            inodes.add(target[8:-1])
    found: dict[str, set[tuple[str, str]]] = {"tcp": set(), "udp": set()}
    for proto in ("tcp", "tcp6", "udp", "udp6"):
        lines = Path(f"/proc/self/net/{proto}").read_text().splitlines()[1:]
        for line in lines:
            f = line.split()
            ip_hex, port_hex = f[1].split(":")
            listening = proto.startswith("udp") or f[3] == "0A"  # 0A: TCP LISTEN
            if f[9] in inodes and listening:
                found[proto[:3]].add((ip_hex, str(int(port_hex, 16))))
    return found


LOOPBACK_HEX = {"0100007F", "00000000000000000000000001000000"}  # 127.0.0.1, ::1


def test_embedded_default_config_is_loopback_peer_without_multicast():
    conf = zenoh_config()
    assert json.loads(conf.get_json("mode")) == "peer"
    assert json.loads(conf.get_json("listen/endpoints")) == [LOOPBACK_LISTEN]
    assert LOOPBACK_LISTEN.startswith("tcp/127.0.0.1:")
    assert json.loads(conf.get_json("scouting/multicast/enabled")) is False
    assert free_loopback_endpoint().startswith("tcp/127.0.0.1:")  # the runner's default


def test_embedded_session_really_listens_on_loopback_only():
    before = _own_sockets()
    bus = ZenohBus(zenoh_config())
    try:
        after = _own_sockets()
    finally:
        bus.close()
    new_tcp = after["tcp"] - before["tcp"]
    assert new_tcp, "the session opened no listening socket"
    assert {ip for ip, _ in new_tcp} <= LOOPBACK_HEX, new_tcp
    # no multicast scouting: no UDP socket on the scouting port 7446
    assert not any(port == "7446" for _, port in after["udp"] - before["udp"])


def test_config_file_mode_and_endpoints_are_kept(tmp_path):
    f = tmp_path / "c.json5"
    f.write_text('{mode: "client", connect: {endpoints: ["tcp/10.1.2.3:7447"]},'
                 ' scouting: {multicast: {enabled: true}}}')
    conf = zenoh_config(["tcp/10.9.9.9:7447"], config_file=str(f))
    assert json.loads(conf.get_json("mode")) == "client"
    assert json.loads(conf.get_json("connect/endpoints")) == ["tcp/10.1.2.3:7447",
                                                               "tcp/10.9.9.9:7447"]
    assert json.loads(conf.get_json("scouting/multicast/enabled")) is True  # the file's choice
    assert json.loads(conf.get_json("connect/timeout_ms")) == CLIENT_CONNECT_TIMEOUT_MS
    assert json.loads(conf.get_json("listen/endpoints")) != [LOOPBACK_LISTEN]  # clients: none
    # an explicit mode wins over the file's; a peer listens on loopback
    conf = zenoh_config(config_file=str(f), mode="peer")
    assert json.loads(conf.get_json("mode")) == "peer"
    assert json.loads(conf.get_json("listen/endpoints")) == [LOOPBACK_LISTEN]


def test_node_started_alone_is_a_client_unless_told(monkeypatch):
    modes = []

    class FakeBus:
        def __init__(self, config):
            modes.append(json.loads(config.get_json("mode")))

        def close(self):
            pass

    monkeypatch.setattr(node_main, "ZenohBus", FakeBus)
    monkeypatch.setattr(node_main, "run_node", lambda *a, **k: 0)
    base = ["plant", "--run", "x", "--connect", "tcp/127.0.0.1:7447"]
    assert node_main.main(base) == 0
    assert node_main.main([*base, "--mode", "peer"]) == 0  # how the runner starts its nodes
    assert modes == ["client", "peer"]
