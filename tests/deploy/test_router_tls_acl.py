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
    text = (DEPLOY / "router.json5").read_text()
    allowed = json.loads(text.split("cert_common_names:")[1].split("]")[0] + "]")
    assert set(allowed) == {"orchestrator", *ch.NODES, *ch.OPTIONAL_NODES}  # not observer
    for name in names:
        conf = zenoh_config(config_file=str(DEPLOY / "clients" / f"{name}.json5"))
        assert conf.get_json("transport/link/tls/connect_certificate") == \
            f'"{CERTS}/{name}.pem"'
        # nodes elsewhere are clients of the router; the orchestrator stays a peer so that
        # the nodes it starts on its machine join it directly
        assert conf.get_json("mode") == ('"peer"' if name == "orchestrator" else '"client"')


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


@pytest.mark.integration
def test_only_run_participants_may_publish(tls, router):
    tap = _session(router, tls / "observer.json5")
    plant = _session(router, tls / "plant.json5")
    intruder = _session(router, tls / "observer.json5")  # a valid certificate, not a node
    try:
        heard: list[bytes] = []
        intruder_heard: list[bytes] = []
        lock = threading.Lock()

        def on_tap(_k, payload):
            with lock:
                heard.append(payload)

        tap.subscribe("suscosim/**", on_tap)
        intruder.subscribe("suscosim/**", lambda _k, p: intruder_heard.append(p))
        good, bad = plant.publisher(KEY), intruder.publisher(KEY)
        deadline = time.monotonic() + 20
        n = 0
        while time.monotonic() < deadline:
            bad(b"forged %d" % n)
            intruder.put(KEY, b"forged put %d" % n)
            good(b"real %d" % n)
            n += 1
            time.sleep(0.02)
            with lock:
                if sum(p.startswith(b"real") for p in heard) >= 50:
                    break
        time.sleep(0.5)  # anything forged still in flight arrives by now
        with lock:
            real = [p for p in heard if p.startswith(b"real")]
            forged = [p for p in heard if p.startswith(b"forged")]
        assert len(real) >= 50, f"the authorised publisher was not heard: {len(real)}"
        assert forged == []
        # the intruder is connected and may observe: it hears the plant
        assert any(p.startswith(b"real") for p in intruder_heard)
    finally:
        for s in (intruder, plant, tap):
            s.close()


@pytest.mark.integration
def test_sessions_without_a_ca_certificate_are_refused(tls, router):
    with pytest.raises(Exception, match="(?i)unable to connect"):
        _session(router, None, mode="client")  # TLS without a client certificate
    plain = router.replace("tls/", "tcp/")
    with pytest.raises(Exception, match="(?i)unable to connect"):
        _session(plain, tls / "plant.json5")  # plain TCP to the TLS port


@pytest.mark.integration
def test_run_through_the_tls_router_and_an_impostor_plant(tls, router, tmp_path):
    """A node on 'another machine' joins through the TLS router with its own certificate; a
    plant node with the observer's certificate cannot take part (the run does not start)."""
    for cert, run_id, start_s in (("plant", "tlsok", 60.0), ("observer", "tlsno", 6.0)):
        node = popen_suscosim("node", "plant", "--run", run_id, "--connect", router,
                              "--zenoh-config", str(tls / f"{cert}.json5"))
        try:
            res = suscosim("run", str(CH3_STEP), "--quiet", "--out", str(tmp_path / run_id),
                           "--connect", router,
                           "--zenoh-config", str(tls / "orchestrator.json5"),
                           "--external", "plant", "--set", f'run.id="{run_id}"',
                           "--set", "run.t_end=0.5", "--set", f"run.start_timeout_s={start_s}",
                           timeout=120)
        finally:
            if node.poll() is None:
                node.terminate()
            node.communicate(timeout=30)
        summary = json.loads((tmp_path / run_id / "summary.json").read_text())
        if cert == "plant":
            assert res.returncode == 0, res.stdout + res.stderr
            assert summary["status"] == "ok" and summary["rows"] == 501
        else:
            assert res.returncode == 1, res.stdout + res.stderr
            assert "not ready" in res.stderr and "'plant' (absent)" in res.stderr, res.stderr
            assert "Traceback" not in res.stderr
            assert summary["status"] == "failed"
