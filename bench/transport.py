"""Transports: coupled steps/s of a run over each, whether a mesh's start wedges, and what a live
tap costs a run. Timing is measured here, never asserted in tests.

    python -m bench transport [--t-end 2.0] [--h 0.001] [--repeat 3] [--only NAME] [--out DIR]
    python -m bench join-stress [--rounds 300] [--peers 5] [--net-workers 1]
                                [--mesh gossip|explicit|server-universal|run] [--dump DIR]
    python -m bench tap-overhead [OUT_DIR] [REPEATS]     (default runs/tap_overhead, 3)

``transport``: coupled steps/s (median and best of ``--repeat`` real ``suscosim run``s of the
Chapter 3 step, start-up excluded) over ``loopback`` (every session a Zenoh peer on loopback,
the embedded default), ``router-peers`` (``suscosim router`` on loopback, ``run --connect``
to it: the nodes still meet directly), ``router-clients`` (the four nodes started alone as
clients of the router, orchestrator ``--external`` for all: every message crosses the router)
and ``netns`` (three Linux network namespaces joined by veth pairs, root only: router, plant
node, the rest, as tests/integration/test_netns.py). A markdown table.

``join-stress``: does a session wedge while peers join at once? Each round starts one
listening peer (the orchestrator's role: a liveliness token and a queryable) and ``--peers``
peer processes at once with suscosim's configuration (:func:`cosim.bus.zenoh_config`), each
doing what a node does first (a token, a ``get`` of the scenario, a subscriber); a peer not
done within 20 s counts as wedged (killed; ``--dump``: its native and Python stacks). That is
Zenoh's routing deadlock under peer churn (eclipse-zenoh/zenoh#2581, fixed upstream by #2779
after 1.10.2). ``--mesh``: ``gossip`` (peers find each other by gossip), ``explicit`` (gossip
off, a full TCP mesh), ``server-universal`` (as gossip, the listening peer on the universal
transport) or ``run`` (what ``suscosim run`` does: the explicit mesh of
:class:`orchestrator.local_mesh.LocalMesh` over Unix sockets, gossip off, server universal,
peers low-latency). ``--net-workers``: ``ZENOH_RUNTIME``'s Net worker count in every process.

``tap-overhead``: does a live tap slow a run down? The Chapter 3 quarter car (distributed,
1 ms, 4 s = 4000 coupled steps), alternately untapped and tapped on everything (``suscosim tap
RUN`` with the CSV of every data message), REPEATS times each: coupled steps/s. Then the first
untapped run's journal replayed as fast as possible into a tap: the replay rate.
Results: docs/tap_replay.md.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from cosim import channels as ch  # noqa: E402
from cosim.bus import free_loopback_endpoint  # noqa: E402

# ---- transport ------------------------------------------------------------------------------
SCENARIO = ROOT / "scenarios" / "ch3_step_quarter_car.toml"
ENV = dict(os.environ, PYTHONPATH=str(ROOT), PYTHONUNBUFFERED="1")


def _cli(*args: str, prefix: list[str] | None = None, **kw) -> subprocess.Popen:
    argv = [*(prefix or []), sys.executable, "-m", "orchestrator", *args]
    return subprocess.Popen(argv, cwd=ROOT, env=ENV, text=True, **kw)


def _run(out: Path, run_id: str, base: list[str], *extra: str,
         prefix: list[str] | None = None) -> float:
    """One ``suscosim run``; its coupled steps/s from summary.json."""
    p = _cli("run", str(SCENARIO), "--quiet", "--out", str(out), "--set", f'run.id="{run_id}"',
             *base, *extra, prefix=prefix, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    stdout, stderr = p.communicate(timeout=600)
    if p.returncode != 0:
        raise RuntimeError(f"run {run_id} failed: {stdout}{stderr}")
    return float(json.loads((out / "summary.json").read_text())["steps_per_s"])


def _router(ep: str, prefix: list[str] | None = None) -> subprocess.Popen:
    r = _cli("router", "--listen", ep, prefix=prefix, stdout=subprocess.PIPE,
             stderr=subprocess.PIPE)
    line = r.stdout.readline()
    if "listening on" not in line:
        raise RuntimeError(f"router did not start: {line}{r.stderr.read()}")
    return r


def _stop(*procs: subprocess.Popen, grace_s: float = 15.0) -> None:
    """SIGTERM every process (an ended one ignores it), then SIGKILL those still running
    ``grace_s`` seconds later: one grace period for them all, not one each."""
    for p in procs:
        p.terminate()
    deadline = time.monotonic() + grace_s
    while any(p.poll() is None for p in procs) and time.monotonic() < deadline:
        time.sleep(0.05)
    for p in procs:
        if p.poll() is None:
            p.kill()
        p.wait()


def loopback_peers(out: Path, run_id: str, base: list[str]) -> float:
    return _run(out, run_id, base)


def router_peers(out: Path, run_id: str, base: list[str]) -> float:
    ep = free_loopback_endpoint()
    r = _router(ep)
    try:
        return _run(out, run_id, base, "--connect", ep)
    finally:
        _stop(r)


def router_clients(out: Path, run_id: str, base: list[str]) -> float:
    ep = free_loopback_endpoint()
    r = _router(ep)
    nodes = []
    try:
        for n in ch.NODES:
            nodes.append(_cli("node", n, "--run", run_id, "--connect", ep,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        ext = [a for n in ch.NODES for a in ("--external", n)]
        return _run(out, run_id, base, "--connect", ep, *ext)
    finally:
        _stop(*nodes, r)


def namespaces(out: Path, run_id: str, base: list[str]) -> float:
    from tests.integration.netns import MAIN, PLANT, ROUTER, ROUTER_ADDR, Topology

    t = Topology()
    try:
        r = _router("tcp/0.0.0.0:7447", prefix=t.cmd(ROUTER, []))
        plant = _cli("node", "plant", "--run", run_id, "--connect",
                     f"tcp/{ROUTER_ADDR[PLANT]}:7447", prefix=t.cmd(PLANT, []),
                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            return _run(out, run_id, base, "--connect", f"tcp/{ROUTER_ADDR[MAIN]}:7447",
                        "--external", "plant", prefix=t.cmd(MAIN, []))
        finally:
            _stop(plant, r)
    finally:
        t.close()


TRANSPORTS: dict[str, tuple[str, Callable[[Path, str, list[str]], float]]] = {
    "loopback": ("loopback peers (embedded default)", loopback_peers),
    "router-peers": ("`suscosim router` on loopback, nodes peers", router_peers),
    "router-clients": ("`suscosim router` on loopback, all nodes clients", router_clients),
    "netns": ("router / plant / rest in 3 network namespaces", namespaces),
}


def transport(args: argparse.Namespace) -> int:
    """``transport``: coupled steps/s over each transport."""
    from tests.integration.netns import unavailable

    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="bench-transport-"))
    base = ["--set", f"run.t_end={args.t_end}", "--set", f"run.h={args.h}"]
    n_steps = round(args.t_end / args.h)
    rows = []
    for key in args.only or list(TRANSPORTS):
        label, fn = TRANSPORTS[key]
        if key == "netns" and (reason := unavailable()):
            rows.append(f"| {label} | skipped: {reason} | |")
            continue
        rates = [fn(out / f"{key}-{i}", f"bt-{key}-{os.getpid()}-{i}", base)
                 for i in range(args.repeat)]
        rows.append(f"| {label} | {statistics.median(rates):.0f} | {max(rates):.0f} |")
        print(f"{key}: {', '.join(f'{r:.0f}' for r in rates)}", file=sys.stderr, flush=True)
    print(f"Chapter 3 step, h = {args.h * 1000:g} ms, {n_steps} coupled steps, "
          f"{args.repeat} runs each; {os.cpu_count()} CPUs, {platform.machine()}, "
          f"Python {platform.python_version()}\n")
    print("| transport | coupled steps/s (median) | best |")
    print("|---|---:|---:|")
    for row in rows:
        print(row)
    return 0


# ---- join-stress ----------------------------------------------------------------------------
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


def join_stress(args: argparse.Namespace) -> int:
    """``join-stress``: rounds of peers joining at once; how many wedged."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    env["ZENOH_RUNTIME"] = f"(net: (worker_threads: {args.net_workers}))"
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


# ---- tap-overhead ---------------------------------------------------------------------------
def _orchestrator(*args: str, **kw) -> subprocess.Popen:
    """``python -m orchestrator ARGS`` in the repository root."""
    return subprocess.Popen([sys.executable, "-m", "orchestrator", *args], cwd=ROOT, env=ENV,
                            **kw)


def _steps_per_s(run: Path) -> str:
    return f"{json.loads((run / 'summary.json').read_text())['steps_per_s']:.0f}"


def _last_line(path: Path) -> str:
    lines = path.read_text(errors="replace").splitlines()
    return lines[-1] if lines else ""


def tap_overhead(args: argparse.Namespace) -> int:
    """``tap-overhead``: untapped against tapped runs, then the replay rate into a tap."""
    out = ROOT / args.out_dir
    out.mkdir(parents=True, exist_ok=True)
    scenario = "scenarios/ch3_step_quarter_car.toml"
    for i in range(1, args.repeats + 1):
        plain, tapped = out / f"plain{i}", out / f"tapped{i}"
        if _orchestrator("run", scenario, "--out", str(plain), "--quiet",
                         stdout=subprocess.DEVNULL).wait():
            raise SystemExit(f"the untapped run {plain} failed")
        run = _orchestrator("run", scenario, "--out", str(tapped), "--quiet", "--listen",
                            free_loopback_endpoint(), stdout=subprocess.DEVNULL)
        while not (tapped / "journal.msgpack").is_file() and run.poll() is None:
            time.sleep(0.05)
        with open(out / f"tap{i}.log", "w") as log:
            tap = _orchestrator("tap", str(tapped), "--duration", "60", "--count", "16004",
                                "--csv", str(out / f"tapped{i}.csv"), stdout=log,
                                stderr=subprocess.STDOUT)
            code = run.wait()
            tap.terminate()
            tap.wait()
        if code:
            raise SystemExit(f"the tapped run {tapped} failed (exit {code})")
        print(f"repeat {i}: untapped {_steps_per_s(plain)} steps/s, tapped "
              f"{_steps_per_s(tapped)} steps/s ({_last_line(out / f'tap{i}.log')})", flush=True)
    ep = free_loopback_endpoint()
    with open(out / "replay_tap.log", "w") as log:
        tap = _orchestrator("tap", "*", "plant/state", "--listen", ep, "--count", "4001",
                            "--duration", "60", stdout=log, stderr=subprocess.STDOUT)
        time.sleep(1.0)
        replay = _orchestrator("replay", str(out / "plain1"), "--fast", "--connect", ep,
                               stderr=subprocess.DEVNULL)
        code = replay.wait()
        tap.wait()
    if code:
        raise SystemExit(f"the replay of {out / 'plain1'} failed (exit {code})")
    print(_last_line(out / "replay_tap.log"))
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="command", required=True)
    p = sub.add_parser("transport", help="coupled steps/s of the Chapter 3 run per transport")
    p.add_argument("--t-end", type=float, default=2.0, help="simulated time [s]")
    p.add_argument("--h", type=float, default=0.001, help="communication step [s]")
    p.add_argument("--repeat", type=int, default=3, help="runs per transport")
    p.add_argument("--only", action="append", choices=sorted(TRANSPORTS),
                   help="measure only these transports (repeatable)")
    p.add_argument("--out", help="run folders (default: a temporary folder)")
    p.set_defaults(fn=transport)
    p = sub.add_parser("join-stress", help="does a Zenoh session wedge while peers join?")
    p.add_argument("--rounds", type=int, default=300)
    p.add_argument("--peers", type=int, default=5)
    p.add_argument("--net-workers", type=int, default=1)
    p.add_argument("--no-lowlatency", action="store_true",
                   help="Zenoh's universal transport instead of the low-latency one")
    p.add_argument("--mesh", choices=("gossip", "explicit", "server-universal", "run"),
                   default="gossip")
    p.add_argument("--dump", type=Path, default=None,
                   help="a folder: the native and Python stacks of each wedged process")
    p.set_defaults(fn=join_stress)
    p = sub.add_parser("tap-overhead", help="a live tap's cost to a run; replay rate into a tap")
    p.add_argument("out_dir", nargs="?", default="runs/tap_overhead",
                   help="run folders and logs (relative: to the repository root)")
    p.add_argument("repeats", nargs="?", type=int, default=3, help="untapped/tapped pairs")
    p.set_defaults(fn=tap_overhead)
    args = ap.parse_args(argv)
    return int(args.fn(args) or 0)


if __name__ == "__main__":
    raise SystemExit(main())
