"""Issue #15 item 4: the router ACL template confines every permission to one run's keys
and to certificates issued for that run."""

from __future__ import annotations

import json

import zenoh

from tests.conftest import ROOT

TEMPLATE = ROOT / "deploy" / "zenoh" / "acl_per_run.json5.template"


def test_the_per_run_acl_template_renders_to_a_router_config_scoped_to_that_run(tmp_path):
    run = "ch3-lab-0001"
    path = tmp_path / "router.json5"
    path.write_text(TEMPLATE.read_text().replace("@RUN@", run))
    conf = zenoh.Config.from_file(str(path))  # Zenoh itself parses it
    acl = json.loads(conf.get_json("access_control"))
    assert acl["enabled"] is True and acl["default_permission"] == "deny"
    exprs = [k for rule in acl["rules"] for k in rule["key_exprs"]]
    assert exprs and all(k.startswith(f"suscosim/{run}/") for k in exprs), exprs
    names = [cn for s in acl["subjects"] for cn in s.get("cert_common_names") or []]
    assert names and all(cn.startswith(f"{run}.") for cn in names), names
    ingress = {r["id"]: r["key_exprs"] for r in acl["rules"] if r["flows"] == ["ingress"]}
    assert ingress["publish-plant"] == [f"suscosim/{run}/plant/**"]
    policies = {p["id"]: p for p in acl["policies"]}
    assert policies["plant"]["rules"] == ["publish-plant"]
    assert "@RUN@" not in path.read_text()
