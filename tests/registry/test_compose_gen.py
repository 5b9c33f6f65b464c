"""The deployment files' per-node parts are what the registry gives
(``python -m orchestrator.compose_gen``): a kind added without regenerating fails here."""

from __future__ import annotations

import dataclasses
import re
import shutil
from pathlib import Path

import pytest

from cosim import node_kinds as nk
from orchestrator import compose_gen

from ..conftest import ROOT

yaml = pytest.importorskip("yaml", reason="pyyaml is in the test extra: pip install -e .[test]")


def test_the_committed_files_are_what_the_registry_gives() -> None:
    assert compose_gen.stale() == [], "run: python -m orchestrator.compose_gen"
    assert compose_gen.main(["--check"]) == 0


def _copy_tree(dst: Path) -> Path:
    for rel in [*compose_gen.regions(), *(f"deploy/zenoh/clients/{n}.json5" for n in nk.names())]:
        (dst / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(ROOT / rel, dst / rel)
    return dst


def test_a_new_kind_appears_everywhere_once_regenerated(tmp_path: Path, monkeypatch) -> None:
    """A listener kind 'logger' added to the registry: stale until regenerated, then a
    compose service (node and machine files), an --external of the orchestrator, a publish
    rule on its own keys, a certificate subject, a policy, a client file, a certificate."""
    root = _copy_tree(tmp_path)
    logger = nk.NodeKind("logger", nk.LISTENER, nk.Impl("mypkg.logger:run"),
                         reads=(("*", "records"),))
    monkeypatch.setattr(nk, "KINDS", (*nk.KINDS, logger))
    monkeypatch.setattr(nk, "BY_NAME", {**nk.BY_NAME, "logger": logger})
    assert "docker-compose.yml" in compose_gen.stale(root)
    for path, text in compose_gen.render(root).items():
        path.write_text(text)
    assert compose_gen.stale(root) == []
    compose = yaml.safe_load((root / "docker-compose.yml").read_text())
    assert compose["services"]["logger"]["command"][:2] == ["node", "logger"]
    orch = compose["services"]["orchestrator"]["command"]
    assert [orch[i + 1] for i, a in enumerate(orch) if a == "--external"] == list(nk.always())
    assert "logger" in yaml.safe_load((root / "deploy/compose/nodes.yml").read_text())["services"]
    router = (root / "deploy/zenoh/router.json5").read_text()
    assert '"suscosim/*/logger/**"' in router
    assert '{ id: "logger", cert_common_names: ["logger"] }' in router
    assert '{ id: "logger", rules: ["publish-logger"], subjects: ["logger"] }' in router
    template = (root / "deploy/zenoh/acl_per_run.json5.template").read_text()
    assert '"suscosim/@RUN@/logger/**"' in template and '"@RUN@.logger"' in template
    assert (root / "deploy/zenoh/clients/logger.json5").read_text().count("logger.pem") == 1
    assert re.search(r'CLIENTS=\$\{CLIENTS:-"[^"]* logger observer"\}',
                     (root / "deploy/zenoh/make_certs.sh").read_text())


def test_the_runs_volume_follows_the_kind(monkeypatch) -> None:
    """Only a kind that writes the run folder mounts the runs volume."""
    services = yaml.safe_load(compose_gen.compose_services().replace("<<: *suscosim", "image: x"))
    assert [n for n, s in services.items() if "runs:/runs" in s.get("volumes", [])] == \
        ["recorder", "orchestrator"]
    moved = {**nk.BY_NAME, "plant": dataclasses.replace(nk.kind("plant"), run_folder=True)}
    monkeypatch.setattr(nk, "BY_NAME", moved)
    services = yaml.safe_load(compose_gen.compose_services().replace("<<: *suscosim", "image: x"))
    assert "runs:/runs" in services["plant"]["volumes"]


def test_a_region_marker_lost_is_named(tmp_path: Path) -> None:
    root = _copy_tree(tmp_path)
    path = root / "deploy/compose/nodes.yml"
    path.write_text(path.read_text().replace(compose_gen.END, "<<< gone"))
    with pytest.raises(SystemExit, match="nodes.yml: expected one region 'services'"):
        compose_gen.render(root)
