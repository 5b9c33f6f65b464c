"""Stress the start of a run's Zenoh mesh: does a session wedge while peers join at once?

    python bench/zenoh_join_stress.py [--rounds 300] [--peers 5] [--net-workers 1|2|0]

Each round starts one listening peer (the orchestrator's role: a liveliness token and a
queryable, as the scenario server) and ``--peers`` peer processes at once, each opened with
suscosim's own configuration (:func:`cosim.bus.zenoh_config`: low latency, gossip to the
greater Zenoh id) and doing what a node does first: a liveliness token, a ``get`` of the
scenario, a subscriber. A peer that has not finished within 20 s is counted as **wedged**
(its process is killed). That is the hang seen twice in a run's start (a node "not ready
within 60 s", its stack in ``Session.get`` or ``declare_token``): Zenoh's routing deadlock
under peer churn (eclipse-zenoh/zenoh#2581, fixed upstream by #2779 after 1.10.2: an RX
thread holding the routing ``ctrl_lock`` waits on the single Net runtime worker, which
waits for that lock).

``--mesh``: ``gossip`` (every session as a run's node: each peer connects to the server and
finds the others by gossip), ``explicit`` (gossip off, a full mesh of given TCP endpoints),
``server-universal`` (as ``gossip``, but the listening peer, the orchestrator's role, on
Zenoh's universal transport: what ``suscosim run`` did on the afternoon of 2026-12-04) or
``run`` (what ``suscosim run`` does since the evening of 2026-12-04: the run's explicit mesh,
:class:`orchestrator.local_mesh.LocalMesh`, over Unix sockets, gossip off, the server
universal and the peers low-latency).

``--net-workers`` sets ``ZENOH_RUNTIME``'s Net worker count in every process (Zenoh's
default is one; :data:`cosim.bus.ZENOH_RUNTIME` is what suscosim sets).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

SERVER = r"""
import sys, time, zenoh
from cosim.bus import zenoh_config
conf = zenoh_config([], [sys.argv[1], *sys.argv[4:]], lowlatency=sys.argv[2] == "1"
                    and sys.argv[3] not in ("server-universal", "run"))
if sys.argv[3] in ("explicit", "run"):
    conf.insert_json5("scouting/gossip/enabled", "false")
s = zenoh.open(conf)
tok = s.liveliness().declare_token("stress/server/alive")
q = s.declare_queryable("stress/server/scenario", lambda query: query.reply(
    "stress/server/scenario", b"x" * 2000))
print("up", flush=True)
sys.stdin.read()
"""

PEER = r"""
import json, os, sys, zenoh
from cosim.bus import zenoh_config
connect, listen = json.loads(sys.argv[1]), json.loads(sys.argv[4])
conf = zenoh_config(connect, listen or None, lowlatency=sys.argv[2] == "1")
if sys.argv[3] in ("explicit", "run"):
    conf.insert_json5("scouting/gossip/enabled", "false")
s = zenoh.open(conf)
tok = s.liveliness().declare_token(f"stress/{os.getpid()}/alive")
got = None
while got is None:
    for r in s.get("stress/server/scenario", timeout=1.0):
        if r.ok is not None:
            got = r.ok.payload.to_bytes()
sub = s.declare_subscriber("stress/**", lambda sample: None)
pub = s.declare_publisher(f"stress/{os.getpid()}/step")
pub.put(b"hello")
print("done", flush=True)
os._exit(0)
"""


def dump_stacks(pid: int, path: Path) -> None:
    """Every thread's native stack of process ``pid`` (gdb) and its Python stack (py-spy),
    into ``path``: where a wedged session waits."""
    with path.open("w") as f:
        for cmd in (["gdb", "-p", str(pid), "-batch", "-ex", "thread apply all bt"],
                    ["py-spy", "dump", "--pid", str(pid)]):
            try:
                res = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
                f.write(f"$ {' '.join(cmd)}\n{res.stdout}\n{res.stderr}\n")
            except (OSError, subprocess.TimeoutExpired) as exc:
                f.write(f"$ {' '.join(cmd)}: {exc}\n")


def one_round(port: int, peers: int, env: dict[str, str], dump: Path | None = None,
              tag: str = "", lowlatency: bool = True, mesh: str = "gossip") -> int:
    """Start the server and ``peers`` peers; return how many peers wedged (their stacks and
    the server's into ``dump``, when given). ``mesh``: ``gossip`` (each peer connects to the
    server and finds the others by gossip, as a run's nodes do) or ``explicit`` (gossip off;
    each peer listens on an endpoint given to it and connects to the server's and to those
    of the peers before it: a full mesh with no link-state messages)."""
    endpoint = f"tcp/127.0.0.1:{port}"
    ll = str(int(lowlatency))
    from orchestrator.local_mesh import ORCHESTRATOR, LocalMesh

    names = [f"peer{i}" for i in range(peers)]
    run_mesh = LocalMesh.create(names) if mesh == "run" else None
    extra = [run_mesh.listen(ORCHESTRATOR)] if run_mesh else []
    server = subprocess.Popen([sys.executable, "-c", SERVER, endpoint, ll, mesh, *extra],
                              cwd=ROOT, env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                              text=True)
    try:
        assert server.stdout is not None and server.stdout.readline().strip() == "up"
        from cosim.bus import free_loopback_endpoint

        own = [free_loopback_endpoint() for _ in range(peers)] if mesh == "explicit" else []
        procs = []
        for i in range(peers):
            if run_mesh is not None:
                connect, listen = run_mesh.connect(names[i]), [run_mesh.listen(names[i])]
            else:
                connect, listen = [endpoint, *own[:i]], own[i:i + 1]
            procs.append(subprocess.Popen(
                [sys.executable, "-c", PEER, json.dumps(connect), ll, mesh, json.dumps(listen)],
                cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                text=True))
        wedged = 0
        deadline = time.monotonic() + 20.0
        for p in procs:
            try:
                p.wait(max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                wedged += 1
                if dump is not None:
                    dump_stacks(p.pid, dump / f"{tag}-peer-{p.pid}.txt")
                    if wedged == 1:
                        dump_stacks(server.pid, dump / f"{tag}-server-{server.pid}.txt")
                p.kill()
                p.wait()
        return wedged
    finally:
        server.kill()
        server.wait()
        if run_mesh is not None:
            run_mesh.remove()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=300)
    ap.add_argument("--peers", type=int, default=5)
    ap.add_argument("--net-workers", type=int, default=1)
    ap.add_argument("--no-lowlatency", action="store_true",
                    help="Zenoh's universal transport instead of the low-latency one")
    ap.add_argument("--mesh", choices=("gossip", "explicit", "server-universal", "run"),
                    default="gossip")
    ap.add_argument("--dump", type=Path, default=None,
                    help="a folder: the native and Python stacks of each wedged process")
    args = ap.parse_args()
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    env["ZENOH_RUNTIME"] = f"(net: (worker_threads: {args.net_workers}))"
    from cosim.bus import free_loopback_endpoint

    if args.dump is not None:
        args.dump.mkdir(parents=True, exist_ok=True)

    wedged_rounds = wedged_peers = 0
    t0 = time.monotonic()
    for i in range(args.rounds):
        port = int(free_loopback_endpoint().rsplit(":", 1)[1])
        w = one_round(port, args.peers, env, args.dump, f"round{i}", not args.no_lowlatency,
                      args.mesh)
        wedged_peers += w
        wedged_rounds += bool(w)
        if w:
            print(f"round {i}: {w} peer(s) wedged", flush=True)
    print(f"net workers {args.net_workers}, lowlatency {not args.no_lowlatency}, "
          f"mesh {args.mesh}: "
          f"{args.rounds} rounds of {args.peers} peers, {wedged_rounds} rounds with a wedged peer "
          f"({wedged_peers} peers), {time.monotonic() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
