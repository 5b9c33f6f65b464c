"""The floor of the architecture: the run's lock-step pattern with no model work. Timing is
measured here, never asserted in tests.

    python -m bench null-chain [--steps 2000] [--repeats 3] [--counts 2,3,4,5]
        [--wires raw,protocol] [--exchanges sequential,parallel] [--pin auto|off] [--work ...]

``null-chain`` (issue #16): the floor of the architecture. The run's nodes (plant, tyre_road,
controller, recorder, fatigue: the first 2-5), each its own process started, linked (the run's
explicit mesh, :class:`orchestrator.local_mesh.LocalMesh`), pinned (``orchestrator.placement``,
recorder and fatigue in ``SCHED_IDLE``, fatigue at nice +10, coupled nodes sharing a core in
``SCHED_BATCH`` with their Zenoh threads on the other core, every coupled node's Zenoh threads
in real time, Zenoh's runtimes as ``cosim.bus.NODE_RUNTIME``) and polling (each kind's
``spin_us``) as the orchestrator does (the node side: ``python -m bench.null_chain nodes
NAME --connect EP``, bench/null_chain_nodes.py);
this process is the orchestrator, with the run's own :class:`orchestrator.clock.Clock`
(steps/s = ``n_steps / step_wall_s``, as summary.json). Per step, as the node shells do
with the Chapter 6 corner's message sizes: the plant puts ONE
message a step (``state`` of step k with ``response`` and ``arm`` of k - 2, #28 item 2) and
waits for each force node's ``force``; tyre_road and the controller wait for ``state`` of step
k (sequential) or k - 1 (parallel); every producer sends its records in batches (64 messages or
50 ms) to the recorder, the fatigue node takes the plant's batches and decodes their ``arm``
(#28 item 4). Wires: ``protocol`` (:class:`cosim.participant.Participant` and
:class:`cosim.listener.Listener`: encode, sign, verify, decode), ``unsigned`` (no run key),
``raw`` (bytes of the same sizes on the same sessions, nothing encoded or checked: Zenoh and
the processes alone). ``--work`` adds model CPU per step by node. The bare round trip
(bench/bench_zenoh_pingpong.py's ``one``: issue #16's callback configuration and the nodes'
FIFO, pinned, polling one) is run before and after; every configuration ``--repeats`` times,
interleaved; median, range and the load average printed.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


from bench.null_chain_nodes import (  # noqa: E402
    EXCHANGES,
    ROLES,
    STALL_S,
    WIRES,
    H,
    _sizes,
    node_main,
)
from cosim.auth import RunKey  # noqa: E402

NODE_CMD = [sys.executable, "-m", "bench.null_chain", "nodes"]
"""A null-chain node process (run in the repository root)."""


# ---- null chain: orchestrator side ----------------------------------------------------------
def _load() -> str:
    """The 1-minute load average now."""
    return Path("/proc/loadavg").read_text().split()[0]


def _send(p: subprocess.Popen, obj: dict[str, Any]) -> None:
    """One command line to a node process."""
    assert p.stdin is not None
    p.stdin.write(json.dumps(obj) + "\n")
    p.stdin.flush()


def _line(p: subprocess.Popen) -> str:
    """The next line a node process prints (stripped)."""
    assert p.stdout is not None
    return str(p.stdout.readline()).strip()


class Chain:
    """The node processes of one configuration (the first ``count`` of :data:`ROLES`), started,
    pinned and connected to this process's Zenoh session as the orchestrator does it."""

    def __init__(self, bus: Any, mesh: Any, count: int, pin: bool) -> None:
        from cosim import node_kinds as nk
        from cosim.bus import NODE_RUNTIME
        from orchestrator import placement as pl

        self.names = list(ROLES[:count])
        cores = pl.core_layout(self.names, pl.usable_cores()) if pin else {}
        shared = pl.sharing_a_core(cores)
        self.procs: dict[str, subprocess.Popen] = {}
        self.cores: dict[str, int] = {}
        for name in self.names:
            spin = pl.spin_us(name, cores) if name in cores else 0
            links = [a for ep in mesh.connect(name) for a in ("--connect", ep)]
            self.procs[name] = p = subprocess.Popen(
                [*NODE_CMD, name, *links, "--listen", mesh.listen(name),
                 "--spin-us", str(spin)], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                text=True, cwd=ROOT, env={"ZENOH_RUNTIME": NODE_RUNTIME, **os.environ,
                                          "PYTHONPATH": str(ROOT)})
            if name in cores and pl.pin(p.pid, cores[name]):
                self.cores[name] = cores[name]
                if name in shared:
                    pl.batch(p.pid)
        for name, p in self.procs.items():
            line = _line(p)
            if line != "up":
                raise RuntimeError(f"null node {name} did not start ({line!r})")
        for name in self.cores:  # as a run does once it has started
            if nk.off_critical_path(name):
                pl.background(self.procs[name].pid)
            else:
                pl.move_zenoh_threads(self.procs[name].pid, pl.zenoh_core(name, self.cores))
        self.bus = bus

    def trial(self, i: int, n: int, exchange: str, wire: str,
              work: dict[str, float] | None = None) -> dict[str, Any]:
        """One run of ``n`` steps: steps/s (``n / step_wall_s``) and each node's CPU per step."""
        from orchestrator.clock import Clock

        run = f"null{len(self.names)}-{wire}-{exchange[:3]}-{i}-{os.getpid()}"
        key = os.urandom(32)
        cmd = {"run": run, "key": key.hex(), "n": n, "exchange": exchange, "wire": wire,
               "nodes": self.names, "sizes": _sizes(key), "work": work or {}}
        scenario = {"run": {"n_steps": n, "h": H, "start_timeout_s": STALL_S,
                            "stall_timeout_s": STALL_S}}
        clock = Clock(self.bus, run, self.names, scenario,
                      auth=None if wire == "unsigned" else RunKey(key),
                      check_processes=self._dead)
        for p in self.procs.values():
            _send(p, cmd)
        try:
            res = clock.run()
        finally:
            clock._token.undeclare()
        cpu = {name: json.loads(_line(p))["cpu_s"] / n * 1e6 for name, p in self.procs.items()}
        return {"steps_per_s": n / res.step_wall_s, "cpu_us": cpu}

    def _dead(self) -> str | None:
        for name, p in self.procs.items():
            if p.poll() is not None:
                return f"null node {name} exited with code {p.returncode}"
        return None

    def close(self) -> None:
        for p in self.procs.values():
            try:
                _send(p, {"quit": True})
            except OSError:
                pass
        for p in self.procs.values():
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()


def _median_range(xs: list[float]) -> str:
    return f"{statistics.median(xs):.0f} ({min(xs):.0f}-{max(xs):.0f})"


def pingpongs(repeats: int, n: int) -> dict[str, list[float]]:
    """Round trips/s of the bare ping-pong, ``repeats`` times in both configurations."""
    from bench.bench_zenoh_pingpong import one

    out: dict[str, list[float]] = {"callback": [], "nodes": []}
    for _ in range(repeats):
        out["callback"].append(1e6 / one(n, fifo=False, ll=True, express=True)["rtt_us"])
        out["nodes"].append(1e6 / one(n, fifo=True, ll=True, express=True, pinned=True)["rtt_us"])
    return out


def null_chain(args: argparse.Namespace) -> int:
    """``null-chain``: steps/s of the null chain against the bare round trip."""
    from cosim.bus import ZenohBus, free_loopback_endpoint, zenoh_config
    from orchestrator.local_nodes import local_lease_ms
    from orchestrator.placement import should_pin, usable_cores

    counts = [int(c) for c in args.counts.split(",")]
    if not all(2 <= c <= len(ROLES) for c in counts):
        print(f"--counts {args.counts}: each must be 2..{len(ROLES)}", file=sys.stderr)
        return 2
    wires, exchanges = args.wires.split(","), args.exchanges.split(",")
    try:
        work = {k: float(v) for k, v in (kv.split("=") for kv in args.work.split(",") if kv)}
    except ValueError:
        print(f"--work {args.work}: expected node=us,node=us", file=sys.stderr)
        return 2
    if not set(work) <= set(ROLES):
        print(f"--work: nodes are {', '.join(ROLES)}", file=sys.stderr)
        return 2
    bad = [w for w in wires if w not in WIRES] + [e for e in exchanges if e not in EXCHANGES]
    if bad:
        print(f"unknown wire or exchange: {', '.join(bad)} (wires: {', '.join(WIRES)}; "
              f"exchanges: {', '.join(EXCHANGES)})", file=sys.stderr)
        return 2
    pin = should_pin(args.pin, usable_cores())
    t0 = time.monotonic()
    print(f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, {os.cpu_count()} CPUs, "
          f"load {_load()}, {args.steps} steps a run, pinned: {pin}, model work per step: "
          f"{args.work or 'none'}", flush=True)
    pp0 = pingpongs(max(1, args.repeats // 2 + 1), args.pingpong_n)
    from orchestrator.local_mesh import ORCHESTRATOR, LocalMesh

    endpoint = free_loopback_endpoint()
    mesh = LocalMesh.create(list(ROLES))  # as a run's: explicit, over Unix sockets, no gossip
    bus = ZenohBus(zenoh_config(listen=[endpoint, mesh.listen(ORCHESTRATOR)],
                                lowlatency=False,  # as a run's orchestrator
                                lease_ms=local_lease_ms(STALL_S), gossip=False))
    rows = []
    try:
        for count in counts:
            chain = Chain(bus, mesh, count, pin)
            try:
                time.sleep(0.5)  # the peers' links settle
                got: dict[tuple[str, str], list[dict]] = {}
                loads = [_load()]
                for i in range(args.repeats):  # interleaved
                    for wire in wires:
                        for exchange in exchanges:
                            got.setdefault((wire, exchange), []).append(
                                chain.trial(i, args.steps, exchange, wire, work))
                    loads.append(_load())
            finally:
                chain.close()
            for (wire, exchange), runs in got.items():
                rows.append((count, wire, exchange, runs, f"{min(loads)}-{max(loads)}"))
                sps = [r["steps_per_s"] for r in runs]
                print(f"  {count} processes, {wire}, {exchange}: {_median_range(sps)} steps/s "
                      f"(load {min(loads)}-{max(loads)})", flush=True)
    finally:
        bus.close()
        mesh.remove()
    pp1 = pingpongs(max(1, args.repeats // 2 + 1), args.pingpong_n)
    pp = {c: pp0[c] + pp1[c] for c in pp0}
    rate = statistics.median(pp["callback"])
    print(f"\nbare Zenoh round trips/s (before and after the chains, median (range)): "
          f"issue #16's configuration (callback, low-latency, express, not pinned) "
          f"{_median_range(pp['callback'])}; the nodes' configuration (FIFO, pinned, polling) "
          f"{_median_range(pp['nodes'])}\n")
    print("\n".join(_table(rows, rate)))
    print(f"\nratio: to issue #16's round-trip rate ({rate:.0f}/s, the median above); "
          f"bench wall {time.monotonic() - t0:.0f} s")
    return 0


def _table(rows: list[tuple[int, str, str, list[dict[str, Any]], str]], rate: float
           ) -> list[str]:
    """The markdown table of the null-chain runs (``rows``), ratios to ``rate`` [1/s]."""
    out = ["| processes | wire | exchange | null-chain steps/s, median (range) | ratio to "
           "round trips/s | CPU per step per process (us, median) | load |",
           "|---|---|---|---|---|---|---|"]
    for count, wire, exchange, runs, load in rows:
        sps = [r["steps_per_s"] for r in runs]
        cpu = ", ".join(f"{n} {statistics.median(r['cpu_us'][n] for r in runs):.0f}"
                        for n in ROLES[:count])
        out.append(f"| {count} | {wire} | {exchange} | {_median_range(sps)} | "
                   f"{statistics.median(sps) / rate:.2f} | {cpu} | {load} |")
    return out



def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="command", required=True)
    p = sub.add_parser("null-chain", help="steps/s of the lock-step pattern with no model work")
    p.add_argument("--steps", type=int, default=2000, help="coupled steps per run")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--counts", default="2,3,4,5", help="process counts, of 2..5")
    p.add_argument("--wires", default="raw,protocol",
                   help="of raw, protocol, unsigned (the protocol without the run key)")
    p.add_argument("--exchanges", default="sequential,parallel")
    p.add_argument("--pin", choices=("auto", "off"), default="auto",
                   help="auto: pinned as the orchestrator pins (2-4 cores), off: not pinned")
    p.add_argument("--pingpong-n", type=int, default=2000)
    p.add_argument("--work", default="",
                   help="CPU of model work per coupled step [us] by node, e.g. plant=145,"
                        "tyre_road=35 (default none: the null chain); spent after a node's "
                        "inputs came (plant, force nodes), per records batch (recorder) or "
                        "per load block (fatigue), in proportion to the steps covered")
    p.set_defaults(fn=null_chain)
    p = sub.add_parser("nodes", help="a null-chain node process (started by null-chain)")
    p.add_argument("name", choices=ROLES)
    p.add_argument("--connect", action="append", required=True)
    p.add_argument("--listen", default=None, help="its socket in the run's explicit mesh")
    p.add_argument("--spin-us", type=float, default=0.0)
    p.set_defaults(fn=lambda a: node_main(a.name, a.connect, a.spin_us, a.listen))
    args = ap.parse_args(argv)
    return int(args.fn(args) or 0)


if __name__ == "__main__":
    raise SystemExit(main())
