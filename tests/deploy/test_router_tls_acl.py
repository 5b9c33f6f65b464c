"""``suscosim router`` and the shipped TLS + access-control deployment, over real Zenoh.

The shipped ``deploy/zenoh/router.json5`` and ``deploy/zenoh/clients/*.json5`` are used as they
are, only their certificate folder (``/etc/suscosim/certs``) pointed at certificates made by
the shipped ``deploy/zenoh/make_certs.sh``.
"""

from __future__ import annotations

import json
import shutil
import socket
import subprocess
import threading
import time
from pathlib import Path

import pytest

from cosim import channels as ch
from cosim.bus import ZenohBus, free_loopback_endpoint, zenoh_config
from orchestrator.router import DEFAULT_LISTEN, router_config

from ..conftest import CH3_STEP, ROOT, popen_suscosim, suscosim

DEPLOY = ROOT / "deploy" / "zenoh"
pytestmark = pytest.mark.usefixtures("shared_run_secret")
CERTS = "/etc/suscosim/certs"
KEY = "suscosim/acltest/plant/state"


@pytest.fixture(scope="module")
def tls(tmp_path_factory) -> Path:
    """Certificates from the shipped script, and the shipped configs pointed at them."""
    if shutil.which("openssl") is None:
        pytest.skip("needs the openssl command to make the test certificates")
    d = tmp_path_factory.mktemp("tls")
    res = subprocess.run(["sh", str(DEPLOY / "make_certs.sh"), str(d / "certs")],
                         capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    for f in [DEPLOY / "router.json5", *sorted((DEPLOY / "clients").glob("*.json5"))]:
        (d / f.name).write_text(f.read_text().replace(CERTS, str(d / "certs")))
    return d


@pytest.fixture
def router(tls):
    """The shipped router configuration on a free loopback TLS port; yields the endpoint."""
    ep = free_loopback_endpoint().replace("tcp/", "tls/")
    proc = popen_suscosim("router", "--config", str(tls / "router.json5"), "--listen", ep)
    try:
        line = proc.stdout.readline()
        assert "listening on" in line, line + proc.stderr.read()
        yield ep
    finally:
        proc.terminate()
        out, err = proc.communicate(timeout=15)
        assert proc.returncode == 0 and "stopped" in out, err  # SIGTERM: a clean stop


def _session(ep: str, config: Path | None, **kw) -> ZenohBus:
    conf = zenoh_config([ep], config_file=str(config) if config else None, **kw)
    conf.insert_json5("connect/timeout_ms", "2000")
    return ZenohBus(conf)


def test_shipped_client_configs_cover_every_participant():
    names = {p.stem for p in (DEPLOY / "clients").glob("*.json5")}
    assert names == {"orchestrator", "observer", *ch.NODES, *ch.OPTIONAL_NODES}
    for name in names:
        conf = zenoh_config(config_file=str(DEPLOY / "clients" / f"{name}.json5"))
        assert conf.get_json("transport/link/tls/connect_certificate") == \
            f'"{CERTS}/{name}.pem"'
        # nodes elsewhere are clients of the router; the orchestrator stays a peer so that
        # the nodes it starts on its machine join it directly
        assert conf.get_json("mode") == ('"peer"' if name == "orchestrator" else '"client"')
    acl = json.loads(router_config(config_file=str(DEPLOY / "router.json5"))[0]
                     .get_json("access_control"))
    assert acl["enabled"] and acl["default_permission"] == "deny"
    publishers = {s["id"]: s["cert_common_names"] for s in acl["subjects"]
                  if s.get("cert_common_names")}
    assert publishers == {n: [n] for n in ("orchestrator", *ch.NODES, *ch.OPTIONAL_NODES)}


def test_router_defaults_to_loopback_and_bad_input_exits_2(tmp_path):
    conf, endpoints = router_config()
    assert endpoints == [DEFAULT_LISTEN] and DEFAULT_LISTEN.startswith("tcp/127.0.0.1:")
    assert conf.get_json("scouting/multicast/enabled") == "false"
    assert conf.get_json("mode") == '"router"'
    res = suscosim("router", "--config", str(tmp_path / "none.json5"))
    assert res.returncode == 2 and "no such file" in res.stderr
    (tmp_path / "bad.json5").write_text("{mode: ")
    res = suscosim("router", "--config", str(tmp_path / "bad.json5"))
    assert res.returncode == 2 and "not a valid Zenoh configuration" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1 and "Traceback" not in res.stderr
    res = suscosim("router", "--listen", "nowhere")
    assert res.returncode == 2 and "nowhere" in res.stderr and "Traceback" not in res.stderr


def test_router_port_in_use_exits_1():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        res = suscosim("router", "--listen", f"tcp/127.0.0.1:{port}", timeout=60)
    assert res.returncode == 1 and "cannot start" in res.stderr and "Traceback" not in res.stderr


def _forgery_test(ep: str, tls: Path, key: str, cert: str) -> tuple[int, int, int]:
    """``plant`` and ``cert`` both publish on ``key``: (real heard, forged heard, heard by
    the forger) at an observer, once the real publisher has been heard 50 times."""
    tap = _session(ep, tls / "observer.json5")
    plant = _session(ep, tls / "plant.json5")
    forger = _session(ep, tls / f"{cert}.json5")  # a valid certificate, not this key's node
    try:
        heard: list[bytes] = []
        forger_heard: list[bytes] = []
        lock = threading.Lock()

        def on_tap(_k, payload):
            with lock:
                heard.append(payload)

        tap.subscribe("suscosim/**", on_tap)
        forger.subscribe("suscosim/**", lambda _k, p: forger_heard.append(p))
        good, bad = plant.publisher(key), forger.publisher(key)
        deadline = time.monotonic() + 20
        n = 0
        while time.monotonic() < deadline:
            bad(b"forged %d" % n)
            forger.put(key, b"forged put %d" % n)
            good(b"real %d" % n)
            n += 1
            time.sleep(0.02)
            with lock:
                if sum(p.startswith(b"real") for p in heard) >= 50:
                    break
        time.sleep(0.5)  # anything forged still in flight arrives by now
        with lock:
            return (sum(p.startswith(b"real") for p in heard),
                    sum(p.startswith(b"forged") for p in heard),
                    sum(p.startswith(b"real") for p in forger_heard))
    finally:
        for s in (forger, plant, tap):
            s.close()


@pytest.mark.integration
@pytest.mark.parametrize("cert", ["observer", "controller"])
def test_only_the_keys_node_may_publish_on_them(tls, router, cert):
    """A tap (observer certificate) and another node (controller) cannot publish on the
    plant's keys; the plant can; both can still observe."""
    real, forged, seen_by_forger = _forgery_test(router, tls, "suscosim/acltest/plant/state",
                                                 cert)
    assert real >= 50, f"the plant was not heard: {real}"
    assert forged == 0
    assert seen_by_forger > 0  # connected, and allowed to observe


@pytest.mark.integration
def test_sessions_without_a_ca_certificate_are_refused(tls, router):
    with pytest.raises(Exception, match="(?i)unable to connect"):
        _session(router, None, mode="client")  # TLS without a client certificate
    plain = router.replace("tls/", "tcp/")
    with pytest.raises(Exception, match="(?i)unable to connect"):
        _session(plain, tls / "plant.json5")  # plain TCP to the TLS port


@pytest.mark.integration
def test_run_through_the_tls_router_and_an_impostor_plant(tls, router, tmp_path):
    """Every node on 'another machine', a client of the TLS router with its own certificate
    (the docker-compose layout): the run completes. A plant node holding the observer's
    certificate cannot take part: the run does not start."""
    for cert, run_id, start_s in (("plant", "tlsok", 60.0), ("observer", "tlsno", 3.0)):
        names = list(ch.NODES) if cert == "plant" else ["plant"]
        nodes = [popen_suscosim("node", n, "--run", run_id, "--connect", router,
                                "--zenoh-config",
                                str(tls / f"{n if cert == 'plant' else cert}.json5"))
                 for n in names]
        try:
            res = suscosim("run", str(CH3_STEP), "--quiet", "--out", str(tmp_path / run_id),
                           "--connect", router,
                           "--zenoh-config", str(tls / "orchestrator.json5"),
                           *[a for n in names for a in ("--external", n)],
                           "--set", f'run.id="{run_id}"',
                           "--set", "run.t_end=0.5", "--set", f"run.start_timeout_s={start_s}",
                           timeout=120)
        finally:
            for node in nodes:
                if node.poll() is None:
                    node.terminate()
                node.communicate(timeout=30)
        summary = json.loads((tmp_path / run_id / "summary.json").read_text())
        if cert == "plant":
            assert res.returncode == 0, res.stdout + res.stderr
            assert summary["status"] == "ok" and summary["rows"] == 501
            assert not (tmp_path / run_id / "logs").exists() or not any(
                (tmp_path / run_id / "logs").iterdir())  # no node started here
        else:
            assert res.returncode == 1, res.stdout + res.stderr
            assert "not ready" in res.stderr and "'plant' (absent)" in res.stderr, res.stderr
            assert "Traceback" not in res.stderr
            assert summary["status"] == "failed"
