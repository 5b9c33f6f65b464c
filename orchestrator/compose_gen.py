"""``python -m orchestrator.compose_gen``: the per-node parts of the deployment files from
:mod:`cosim.node_kinds` (compose services, router ACL rules, subjects and policies, client
configurations, certificate names): only the regions between ``>>> generated``/``<<<
generated`` lines (and the client files). ``--check``: write nothing, exit 1 naming stale files.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

from cosim import node_kinds as nk

ROOT = Path(__file__).resolve().parent.parent
BEGIN, END = ">>> generated", "<<< generated"
NOTE = "by python -m orchestrator.compose_gen from cosim/node_kinds.py: do not edit"
SCENARIO = "scenarios/ch3_step_quarter_car.toml"


def _externals(indent: str) -> list[str]:
    args = [f'"--external", "{n}"' for n in nk.always()]
    return [indent + ", ".join(args[i:i + 2]) + "," for i in range(0, len(args), 2)]


def compose_services() -> str:
    """docker-compose.yml: the node services and the orchestrator."""
    run = "${RUN_ID:-ch3-compose}"
    out = _node_services("suscosim", run, "tls/router:7447", [
        "    volumes:  # writes the journal and the tables into the run folder",
        "      - certs:/etc/suscosim/certs:ro", "      - runs:/runs"])
    out += ["  orchestrator:", "    <<: *suscosim",
            f'    command: ["run", "{SCENARIO}",',
            '              "--connect", "tls/router:7447",',
            '              "--zenoh-config", "deploy/zenoh/clients/orchestrator.json5",',
            *_externals("              "),
            f'              "--set", "run.id=\\"{run}\\"",',
            f'              "--out", "/runs/{run}", "--quiet"]',
            "    # interrupted mid-run (docker compose down), the orchestrator writes "
            "summary.json",
            "    # (and the table of a journal up to 4 MB) before it exits: under a second "
            "measured;",
            "    # the longer grace than the engine's 10 s is a margin for a slow volume",
            "    stop_grace_period: 60s",
            "    volumes:", "      - certs:/etc/suscosim/certs:ro", "      - runs:/runs"]
    return "\n".join(out) + "\n"


_RUN_ID = "${RUN_ID:?set RUN_ID (the orchestrator's run id)}"
_ROUTER = "${SUSCOSIM_ROUTER:?set SUSCOSIM_ROUTER, e.g. tls/ROUTER_HOST:7447}"
_CERTS = "${SUSCOSIM_CERTS:-/etc/suscosim/certs}:/etc/suscosim/certs:ro"
_RUNS = "${SUSCOSIM_RUNS:-./runs}:/runs"


def _node_services(anchor: str, run: str, router: str, volumes: list[str]) -> list[str]:
    """A service per node kind (``volumes`` for those writing into the run folder)."""
    out: list[str] = []
    for name in nk.always():
        out += [f"  {name}:", f"    <<: *{anchor}",
                f'    command: ["node", "{name}", "--run", "{run}",',
                f'              "--connect", "{router}",',
                f'              "--zenoh-config", "deploy/zenoh/clients/{name}.json5"]']
        out += volumes if nk.kind(name).run_folder else []
        out.append("")
    return out


def machine_nodes() -> str:
    """deploy/compose/nodes.yml: one service per node of every run."""
    out = _node_services("node", _RUN_ID, _ROUTER, ["    volumes:", f"      - {_CERTS}",
                                                    f"      - {_RUNS}"])
    return "\n".join(out[:-1]) + "\n"


def machine_orchestrator() -> str:
    """deploy/compose/orchestrator.yml: the orchestrator's service."""
    out = ["  orchestrator:", "    image: ${SUSCOSIM_IMAGE:-suscosim:latest}", "    init: true",
           "    environment:", "      SUSCOSIM_KEY_FILE: /etc/suscosim/certs/suscosim.key",
           f'    command: ["run", "${{SCENARIO:-{SCENARIO}}}",',
           f'              "--connect", "{_ROUTER}",',
           '              "--zenoh-config", "deploy/zenoh/clients/orchestrator.json5",',
           *_externals("              "),
           '              "--set", "run.id=\\"${RUN_ID:?set RUN_ID}\\"",',
           '              "--out", "/runs/${RUN_ID:?set RUN_ID}", "--quiet"]',
           "    stop_grace_period: 60s   # a margin: interrupted, it writes summary.json first",
           "    volumes:", f"      - {_CERTS}", f"      - {_RUNS}"]
    return "\n".join(out) + "\n"


def acl_rules(run: str) -> str:
    """Each kind's publish rule (``run``: ``*`` for every run, ``@RUN@`` in the template)."""
    out: list[str] = []
    for name in nk.names():
        out += ["      {", f'        id: "publish-{name}",', '        permission: "allow",',
                '        flows: ["ingress"],',
                '        messages: ["put", "delete", "liveliness_token", "declare_queryable", '
                '"reply"],',
                f'        key_exprs: ["suscosim/{run}/{name}/**"],', "      },"]
    return "\n".join(out) + "\n"


def acl_subjects(prefix: str) -> str:
    """Each kind's certificate subject (common name ``<prefix><kind>``)."""
    return "".join(f'      {{ id: "{n}", cert_common_names: ["{prefix}{n}"] }},\n'
                   for n in nk.names())


def acl_members() -> str:
    names = ", ".join(f'"@RUN@.{n}"' for n in ("orchestrator", *nk.names(), "observer"))
    return f'      {{ id: "members", cert_common_names: [{names}] }},\n'


def acl_policies() -> str:
    return "".join(f'      {{ id: "{n}", rules: ["publish-{n}"], subjects: ["{n}"] }},\n'
                   for n in nk.names())


CLIENT = """// Zenoh client configuration of the {name} node, for a router
// configured with deploy/zenoh/router.json5. Certificate common name: {name}
// (may publish on suscosim/<run>/{name}/** only).
// Certificates from deploy/zenoh/make_certs.sh, in /etc/suscosim/certs (edit if elsewhere).
// Generated {note}.
{{
  mode: "client",
  transport: {{
    link: {{
      tls: {{
        root_ca_certificate: "/etc/suscosim/certs/ca.pem",
        connect_certificate: "/etc/suscosim/certs/{name}.pem",
        connect_private_key: "/etc/suscosim/certs/{name}-key.pem",
        enable_mtls: true,
      }},
    }},
  }},
}}
"""
"""deploy/zenoh/clients/<name>.json5 of a node kind (``CLIENT.format(name=..., note=NOTE)``)."""


def cert_names() -> str:
    names = " ".join(("orchestrator", *nk.names(), "observer"))
    return f'CLIENTS=${{CLIENTS:-"{names}"}}\n'


def regions() -> dict[str, dict[str, str]]:
    return {
        "docker-compose.yml": {"services": compose_services()},
        "deploy/compose/nodes.yml": {"services": machine_nodes()},
        "deploy/compose/orchestrator.yml": {"services": machine_orchestrator()},
        "deploy/zenoh/router.json5": {"rules": acl_rules("*"), "subjects": acl_subjects(""),
                                      "policies": acl_policies()},
        "deploy/zenoh/acl_per_run.json5.template": {
            "rules": acl_rules("@RUN@"),
            "subjects": acl_members() + '      { id: "orchestrator", cert_common_names: '
                                        '["@RUN@.orchestrator"] },\n' + acl_subjects("@RUN@."),
            "policies": acl_policies()},
        "deploy/zenoh/make_certs.sh": {"names": cert_names()},
    }


def fill(text: str, regs: dict[str, str], path: str) -> str:
    """``text`` with each marked region's body replaced (the markers' lines kept)."""
    for region, body in regs.items():
        pat = re.compile(rf"(?m)^([ \t]*(?:#|//) {re.escape(BEGIN)} {re.escape(region)}\b[^\n]*\n)"
                         rf"(.*?)"
                         rf"^([ \t]*(?:#|//) {re.escape(END)} {re.escape(region)}\b[^\n]*\n)",
                         re.S)
        found = pat.findall(text)
        if len(found) != 1:
            raise SystemExit(f"{path}: expected one region '{region}' between "
                             f"'{BEGIN} {region}' and '{END} {region}' lines, found "
                             f"{len(found)}")
        head, old, tail = found[0]
        text = text.replace(head + old + tail, head + body + tail, 1)
    return text


def render(root: Path = ROOT) -> dict[Path, str]:
    out = {root / rel: fill((root / rel).read_text(), regs, rel) for rel, regs in regions().items()}
    for name in nk.names():
        out[root / "deploy/zenoh/clients" / f"{name}.json5"] = CLIENT.format(name=name, note=NOTE)
    return out


def stale(root: Path = ROOT) -> list[str]:
    """The generated files that differ from what the registry gives (relative paths)."""
    return sorted(str(p.relative_to(root)) for p, text in render(root).items()
                  if not p.exists() or p.read_text() != text)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m orchestrator.compose_gen",
                                 description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true",
                    help="write nothing; exit 1 naming the files that are not up to date")
    args = ap.parse_args(argv)
    if args.check:
        bad = stale()
        for rel in bad:
            print(f"{rel}: not what cosim/node_kinds.py gives: run python -m "
                  "orchestrator.compose_gen", file=sys.stderr)
        return 1 if bad else 0
    for path, text in render().items():
        if not path.exists() or path.read_text() != text:
            path.write_text(text)
            print(f"wrote {path.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
