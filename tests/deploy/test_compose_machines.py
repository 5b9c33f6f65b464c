"""Multi-machine compose files (``deploy/compose/``): one file per machine.

``router.yml`` (the router, TLS + access control), ``nodes.yml`` (node containers, each a
TLS client of ``$SUSCOSIM_ROUTER`` with its own certificate), ``orchestrator.yml`` (the run,
every node external). Checked through the compose CLI's own ``config`` (so the files are
what compose accepts, variables interpolated) and the real suscosim CLI parsers; with a
Docker engine (marker ``docker``) the three run for real as three compose projects that
share only a network, like three machines on a LAN.
"""

from __future__ import annotations

import functools
import json
import os
import subprocess
import time
from pathlib import Path

import pytest

from cosim import channels as ch
from orchestrator.cli import build_parser
from orchestrator.router import router_config

from ..conftest import ROOT
from . import docker_env as de
from .test_compose import CERTS, _mounts, _node_config

yaml = pytest.importorskip("yaml", reason="pyyaml is in the test extra: pip install -e .[test]")

MACHINES = ROOT / "deploy" / "compose"
ENV = {"SUSCOSIM_ROUTER": "tls/lab-router.example:7447", "RUN_ID": "ch3-lab",
       "SUSCOSIM_CERTS": "/srv/suscosim/certs", "SUSCOSIM_RUNS": "/srv/suscosim/runs"}


def _config(*files: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess:
    cmd = de.compose_command()
    if isinstance(cmd, str):
        pytest.skip(f"compose CLI needed to validate the files: {cmd}")
    argv = [*cmd]
    for f in files:
        argv += ["-f", str(MACHINES / f)]
    clean = {k: v for k, v in os.environ.items() if k not in ENV}
    return subprocess.run([*argv, "config"], capture_output=True, text=True, cwd=ROOT,
                          env={**clean, **(env if env is not None else ENV)}, timeout=60)


@functools.cache
def _services(*files: str) -> dict:
    res = _config(*files)
    assert res.returncode == 0, res.stderr
    return yaml.safe_load(res.stdout)["services"]


def _mount_sources(service: dict) -> dict[str, str]:
    """Container path -> source, from compose config's output (short or long syntax)."""
    out = {}
    for spec in service.get("volumes", []):
        if isinstance(spec, dict):
            out[spec["target"]] = spec["source"]
        else:
            out.update({t: s for t, s in _mounts({"volumes": [spec]}).items()})
    return out


def test_router_file_mounts_the_shipped_config_and_this_machines_certificates():
    router = _services("router.yml")["router"]
    assert router["image"].startswith("eclipse/zenoh:1.")
    assert router["init"] is True
    mounts = _mount_sources(router)
    assert Path(mounts["/etc/zenoh/router.json5"]).resolve() == ROOT / "deploy/zenoh/router.json5"
    assert mounts[CERTS] == ENV["SUSCOSIM_CERTS"]
    own = _services("router.yml", "router.suscosim.yml")["router"]
    assert own["entrypoint"] == ["suscosim"]
    args, _ = build_parser().parse_known_args(own["command"])
    assert args.module == "orchestrator.router"
    config = own["command"][own["command"].index("--config") + 1]
    assert mounts[config] == mounts["/etc/zenoh/router.json5"]  # the same shipped file
    _, endpoints = router_config(None, str(ROOT / "deploy/zenoh/router.json5"))
    assert endpoints == ["tls/[::]:7447"]  # the port the file publishes


def test_node_file_connects_every_node_to_the_router_from_the_environment(monkeypatch):
    services = _services("nodes.yml")
    assert set(services) == set(ch.NODES)
    for name, svc in services.items():
        cmd = svc["command"]
        assert cmd[:2] == ["node", name] and svc["init"] is True
        seen, conf = _node_config(monkeypatch, cmd[1:])
        assert seen["name"] == name and seen["run"] == ENV["RUN_ID"]
        assert ENV["SUSCOSIM_ROUTER"] in conf.get_json("connect/endpoints")
        assert conf.get_json("mode") == '"client"'
        assert f'"{CERTS}/{name}.pem"' == conf.get_json(
            "transport/link/tls/connect_certificate")
        assert _mount_sources(svc)[CERTS] == ENV["SUSCOSIM_CERTS"]
        assert svc["environment"]["SUSCOSIM_KEY_FILE"] == f"{CERTS}/suscosim.key"
    assert _mount_sources(services["recorder"])["/runs"] == ENV["SUSCOSIM_RUNS"]


def test_orchestrator_file_runs_every_node_external_through_the_router():
    svc = _services("orchestrator.yml")["orchestrator"]
    args = build_parser().parse_args(svc["command"])
    assert args.command == "run" and sorted(args.external) == sorted(ch.NODES)
    assert args.connect == [ENV["SUSCOSIM_ROUTER"]]
    assert (ROOT / args.zenoh_config).is_file() and (ROOT / args.scenario).is_file()
    assert args.out == f"/runs/{ENV['RUN_ID']}"
    assert _mount_sources(svc)["/runs"] == ENV["SUSCOSIM_RUNS"]
    assert svc["environment"]["SUSCOSIM_KEY_FILE"] == f"{CERTS}/suscosim.key"


@pytest.mark.parametrize("missing", ["SUSCOSIM_ROUTER", "RUN_ID"])
def test_a_missing_router_or_run_id_is_refused_naming_it(missing):
    env = {k: v for k, v in ENV.items() if k != missing}
    for f in ("nodes.yml", "orchestrator.yml"):
        res = _config(f, env=env)
        assert res.returncode != 0 and f"set {missing}" in res.stderr, (f, res.stderr)


@pytest.mark.docker
@pytest.mark.long
def test_three_machines_as_three_compose_projects_run_the_default_scenario(tmp_path):
    """Router, nodes and orchestrator from their own files, as three projects that share
    only a network (a LAN): the nodes reach the router by its name on that network, over
    TLS with the certificates of a host folder; the run folder is a host folder."""
    reason = de.unavailable()
    if reason:
        pytest.skip(f"docker tests need a Docker engine: {reason}")
    de.build_image()
    tag = f"lab{os.getpid()}"
    lan = f"suscosim-{tag}"
    certs, runs = tmp_path / "certs", tmp_path / "runs"
    made = subprocess.run(["sh", str(ROOT / "deploy/zenoh/make_certs.sh"), str(certs),
                           "lab-router"], capture_output=True, text=True, timeout=120)
    assert made.returncode == 0, made.stderr
    runs.mkdir()
    net = tmp_path / "lan.yml"  # every project's default network is the shared one
    net.write_text(yaml.safe_dump({"networks": {"default": {"external": True, "name": lan}}}))
    alias = tmp_path / "alias.yml"  # the router's name on the LAN (in its certificate)
    alias.write_text(yaml.safe_dump({"services": {"router": {"networks": {
        "default": {"aliases": ["lab-router"]}}}}}))
    env = {"SUSCOSIM_ROUTER": "tls/lab-router:7447", "RUN_ID": f"{tag}-run",
           "SUSCOSIM_CERTS": str(certs), "SUSCOSIM_RUNS": str(runs),
           "ROUTER_PORT": str(de.free_port())}
    router = de.Project(f"{tag}-a", [MACHINES / "router.yml", MACHINES / "router.suscosim.yml",
                                     net, alias], env)
    nodes = de.Project(f"{tag}-b", [MACHINES / "nodes.yml", net], env)
    orch = de.Project(f"{tag}-c", [MACHINES / "orchestrator.yml", net], env)
    for p in (router, nodes, orch):
        p.argv[p.argv.index("--project-directory") + 1] = str(MACHINES)
    assert subprocess.run(["docker", "network", "create", lan], capture_output=True,
                          timeout=60).returncode == 0
    try:
        router.compose("up", "-d", "--no-build")
        nodes.compose("up", "-d", "--no-build")
        orch.compose("up", "-d", "--no-build")
        cid = orch.container("orchestrator")
        deadline = time.monotonic() + 300
        while de.inspect(cid)["State"]["Running"] and time.monotonic() < deadline:
            time.sleep(0.2)
        state = de.inspect(cid)["State"]
        logs = orch.logs() + nodes.logs() + router.logs()
        assert not state["Running"] and state["ExitCode"] == 0, logs[-4000:]
        summary = json.loads((runs / env["RUN_ID"] / "summary.json").read_text())
        assert summary["status"] == "ok" and summary["n_steps"] == 4000, summary
        for name in ch.NODES:
            assert de.inspect(nodes.container(name))["State"]["ExitCode"] == 0, name
    finally:
        for p in (orch, nodes, router):
            p.down()
        subprocess.run(["docker", "network", "rm", lan], capture_output=True, timeout=60)
