"""docker-compose.yml and Dockerfile: what can be checked without a Docker engine.

The compose file parses; every service's command is a valid ``suscosim`` invocation (parsed
by the real CLI parsers); the node services are exactly the run's nodes; the router is the
official image with the shipped configuration mounted; paths agree across containers.
"""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

from cosim import channels as ch
from cosim import scenario as sc
from orchestrator import node_main
from orchestrator.cli import build_parser

from ..conftest import ROOT

yaml = pytest.importorskip("yaml", reason="pyyaml is in the test extra: pip install -e .[test]")

COMPOSE = ROOT / "docker-compose.yml"
CERTS = "/etc/suscosim/certs"  # where deploy/zenoh/*.json5 read the certificates
ROUTER_EP = "tls/router:7447"
_VAR = re.compile(r"\$\{(\w+)(?::?-([^}]*))?\}")


def _interpolate(value):
    """Compose's ``${VAR:-default}`` with no VAR set in the environment."""
    if isinstance(value, str):
        return _VAR.sub(lambda m: m.group(2) or "", value)
    if isinstance(value, list):
        return [_interpolate(v) for v in value]
    if isinstance(value, dict):
        return {k: _interpolate(v) for k, v in value.items()}
    return value


@pytest.fixture(scope="module")
def compose() -> dict:
    return _interpolate(yaml.safe_load(COMPOSE.read_text()))


def _mounts(service: dict) -> dict[str, str]:
    """Container path -> source of each volume of a service (short syntax)."""
    out = {}
    for spec in service.get("volumes", []):
        source, target = spec.split(":")[:2]
        out[target] = source
    return out


def _node_config(monkeypatch, argv: list[str]) -> tuple[dict, object]:
    """Parse ``suscosim node ...`` with the real CLI and build its Zenoh config; no session."""
    seen: dict = {}

    class FakeBus:
        def __init__(self, config):
            seen["config"] = config

        def close(self):
            pass

    def fake_run_node(bus, run_id, name, scenario=None, spin_s=0.0):
        seen.update(run=run_id, name=name, spin_s=spin_s)
        return 0

    monkeypatch.setattr(node_main, "ZenohBus", FakeBus)
    monkeypatch.setattr(node_main, "run_node", fake_run_node)
    monkeypatch.chdir(ROOT)  # the image's WORKDIR holds the repository's files
    assert node_main.main(argv) == 0
    return seen, seen["config"]


def test_services_are_the_router_the_nodes_and_the_orchestrator(compose):
    services = set(compose["services"])
    assert services == {"certs", "router", "orchestrator", *ch.NODES}


def test_router_is_the_official_image_with_the_shipped_config(compose):
    router = compose["services"]["router"]
    image, _, tag = router["image"].partition(":")
    assert image == "eclipse/zenoh" and tag.split(".")[0] == "1"  # pip eclipse-zenoh is 1.x
    mounts = _mounts(router)
    config_path = next(t for t, s in mounts.items() if s.endswith("deploy/zenoh/router.json5"))
    assert (ROOT / mounts[config_path]).resolve() == ROOT / "deploy/zenoh/router.json5"
    cmd = router["command"]
    assert cmd[cmd.index("-c") + 1] == config_path
    assert mounts[CERTS] == "certs"  # the certificates the config names
    text = (ROOT / "deploy/zenoh/router.json5").read_text()
    assert set(re.findall(r'"(/[^"]+\.pem)"', text)) == {
        f"{CERTS}/ca.pem", f"{CERTS}/router.pem", f"{CERTS}/router-key.pem"}
    assert "7447:7447" in router["ports"]


def test_certs_service_runs_the_shipped_script(compose):
    certs = compose["services"]["certs"]
    assert certs["entrypoint"][1] == "deploy/zenoh/make_certs.sh"
    assert (ROOT / certs["entrypoint"][1]).is_file()
    assert certs["entrypoint"][2] == CERTS and _mounts(certs)[CERTS] == "certs"
    for name in ("router", "orchestrator", *ch.NODES):
        assert compose["services"][name]["depends_on"]["certs"]["condition"] == \
            "service_completed_successfully"


def test_every_participant_gets_the_deployment_secret_made_by_certs(compose, tmp_path):
    """Run messages are signed (cosim/auth.py): every participant derives the run key from
    the same secret, which the certs service writes (mode 600) into the certs volume."""
    for name in ("orchestrator", *ch.NODES):
        svc = compose["services"][name]
        key_file = svc["environment"]["SUSCOSIM_KEY_FILE"]
        assert key_file == f"{CERTS}/suscosim.key" and _mounts(svc)[CERTS] == "certs"
    script = ROOT / "deploy/zenoh/make_certs.sh"
    if shutil.which("openssl") is None:
        pytest.skip("openssl not installed: make_certs.sh not run")
    res = subprocess.run(["sh", str(script), str(tmp_path / "c")], capture_output=True,
                         text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    key = tmp_path / "c" / "suscosim.key"
    assert key.stat().st_mode & 0o777 == 0o600 and len(bytes.fromhex(key.read_text())) == 32


def test_node_commands_parse_and_name_their_node(compose, monkeypatch):
    run_ids = set()
    for name in ch.NODES:
        svc = compose["services"][name]
        cmd = svc["command"]
        assert cmd[:2] == ["node", name]
        args, rest = build_parser().parse_known_args(cmd)
        assert args.module == "orchestrator.node_main" and not rest
        seen, conf = _node_config(monkeypatch, cmd[1:])
        assert seen["name"] == name
        run_ids.add(seen["run"])
        # a client of the router (Zenoh routers do not relay between two peers), over TLS
        # with this node's own certificate (its common name is what the router's ACL checks)
        assert conf.get_json("mode") == '"client"'
        assert ROUTER_EP in conf.get_json("connect/endpoints")
        assert f'"{CERTS}/{name}.pem"' == conf.get_json(
            "transport/link/tls/connect_certificate")
        assert _mounts(svc)[CERTS] == "certs"
    orch = build_parser().parse_args(compose["services"]["orchestrator"]["command"])
    scenario = sc.load(ROOT / orch.scenario, orch.set)
    assert run_ids == {scenario["run"]["id"]}  # the nodes join the orchestrator's run


def test_orchestrator_command_runs_the_default_scenario_with_every_node_external(compose):
    svc = compose["services"]["orchestrator"]
    args = build_parser().parse_args(svc["command"])
    assert args.command == "run" and args.mode is None
    assert (ROOT / args.scenario).resolve() == ROOT / "scenarios/ch3_step_quarter_car.toml"
    assert sorted(args.external) == sorted(ch.NODES)
    assert args.connect == [ROUTER_EP]
    assert (ROOT / args.zenoh_config).is_file()
    scenario = sc.load(ROOT / args.scenario, args.set)
    run_id = scenario["run"]["id"]
    assert run_id and args.out == f"/runs/{run_id}"
    # the recorder (another container) writes the journal into the folder the orchestrator
    # resolves: the same volume at the same path in both
    rec = _mounts(compose["services"]["recorder"])
    orch = _mounts(svc)
    assert rec["/runs"] == orch["/runs"] == "runs" and "runs" in compose["volumes"]


def test_dockerfile_builds_offline_from_the_debootstrap_base():
    """The image needs no registry: FROM the imported debootstrap base, pip --no-index."""
    text = (ROOT / "Dockerfile").read_text()
    base = re.search(r"(?m)^ARG BASE=(\S+)\s*$", text)
    assert base and base.group(1) == "suscosim-base:bookworm"
    script = (ROOT / "deploy/docker/build_base.sh").read_text()
    assert 'TAG="${SUSCOSIM_BASE:-suscosim-base:bookworm}"' in script  # what it tags
    assert "--variant=minbase" in script and "docker import" in script
    froms = re.findall(r"(?m)^FROM (\S+)", text)
    assert froms and all(f in ("${BASE}", "deps") for f in froms)  # no registry image
    installs = re.findall(r"bin/pip (?:install|wheel)[^\n]*", text)
    assert len(installs) == 3 and all("--no-index" in i for i in installs)
    assert re.search(r"(?m)^COPY build/wheelhouse /wheels\s*$", text)
    assert re.search(r"(?m)^WORKDIR /app\s*$", text)  # commands use repository-relative paths
    for path in ("cosim", "nodes", "orchestrator", "scenarios", "deploy", "pyproject.toml"):
        assert re.search(rf"(?m)^COPY .*\b{re.escape(path)}\b", text), path
    assert 'ENTRYPOINT ["suscosim"]' in text
    # the build context keeps what the Dockerfile copies and leaves out the large folders
    ignore = (ROOT / ".dockerignore").read_text().split()
    assert ignore[ignore.index("*") + 1:].count("!build/wheelhouse") == 1
    assert "!sweeps" not in ignore and "!runs" not in ignore


def test_every_service_runs_under_an_init(compose):
    """Python as PID 1 ignores SIGTERM: without an init, 'down' waits for the kill."""
    for name, svc in compose["services"].items():
        assert svc.get("init") is True, name


def test_docker_compose_config_accepts_the_file():
    from .docker_env import compose_command

    cmd = compose_command()
    if isinstance(cmd, str):
        pytest.skip(f"'docker compose config' not available here: {cmd}")
    res = subprocess.run([*cmd, "-f", str(COMPOSE), "config", "-q"],
                         capture_output=True, text=True, cwd=Path(COMPOSE).parent)
    assert res.returncode == 0, res.stderr
