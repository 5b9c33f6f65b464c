"""The protocol's cost: the lock-step pattern of a coupled step with no model work, the wire per
message, and message authentication. Timing is measured here, never asserted in tests.

    python -m bench null-chain [--steps 2000] [--repeats 3] [--counts 2,3,4,5]
        [--wires raw,protocol] [--exchanges sequential,parallel] [--pin auto|off] [--work ...]
    python -m bench wire [--n 20000]
    python -m bench auth [--pairs 5] [--t-end 4.0] [--rev HEAD]

``null-chain`` (issue #16): the floor of the architecture. The run's nodes (plant, tyre_road,
controller, recorder, fatigue: the first 2-5), each its own process started, linked (the run's
explicit mesh, :class:`orchestrator.local_mesh.LocalMesh`), pinned (``orchestrator.placement``,
recorder and fatigue in ``SCHED_IDLE``, fatigue at nice +10) and polling
(``PINNED_SPIN_US``) as the orchestrator does (the node side: ``python -m bench.protocol nodes
NAME --connect EP``); this process is the orchestrator, with the run's own
:class:`orchestrator.clock.Clock` (steps/s = ``n_steps / step_wall_s``, as summary.json). Per
step, as the node shells do with the Chapter 6 corner's message sizes: the plant puts ONE
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

``wire`` (issue #28 item 1): microseconds per call in one warm process (median of five
``timeit`` rounds of ``--n``): (1) the run's codec (:mod:`cosim.wire`, msgspec, bounds checked
in C) against msgpack with the same checks in Python, on the plant's ``state`` and 16-field
``arm`` (the null chain's payloads; both must refuse NaN); (2) keyed BLAKE2b sign and verify
(:class:`cosim.auth.RunKey`) of the plant's step message; (3) a coupled step's protocol work of
the plant and of a force node without the bus. In the null chain the same work costs two to
three times as much (cold code after every process switch; docs/cosim.md).

``auth`` (issue #15 item 4): (1) sign and verify of a quarter-car ``plant/state`` against its
encode and decode [us]; (2) coupled steps/s of the Chapter 3 quarter car
(``scenarios/ch3_step_quarter_car.toml``, distributed) from two copies of the tree (``git
archive REV``): A as it is, B with :class:`cosim.auth.RunKey` replaced by one that neither
signs nor verifies, run A B B A ... so that a drift of the machine hits both; each pair and the
median ratio printed. A failed run's folder is kept and named.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import struct
import subprocess
import sys
import tarfile
import tempfile
import time
import timeit
from collections.abc import Callable
from io import BytesIO
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import msgpack  # noqa: E402
import numpy as np  # noqa: E402

from cosim import keys, schema  # noqa: E402
from cosim.auth import RunKey  # noqa: E402
from cosim.errors import WireError  # noqa: E402
from cosim.wire import SCHEMA_VERSION, codec, decode, encode, encode_step, inner  # noqa: E402

NODE_CMD = [sys.executable, "-m", "bench.protocol", "nodes"]
"""A null-chain node process (run in the repository root)."""

# ---- the null chain's nodes and payloads ----------------------------------------------------
ROLES = ("plant", "tyre_road", "controller", "recorder", "fatigue")
FORCE_NODES = ("tyre_road", "controller")
WIRES = ("raw", "protocol", "unsigned")
EXCHANGES = ("sequential", "parallel")
H = 0.0005
"""The Chapter 6 step [s] (only the start's plausibility check and t = k h use it)."""
STALL_S = 30.0
MAGIC = b"NUL0"
_K = struct.Struct("<q")
CPU: list[float] = []
"""process_time() when this node's stepping began and ended (its CPU per step is taken on it:
the start barrier and the wait for the end are left out)."""
_BATCH = struct.Struct("<qiii")
"""A raw records batch's head after MAGIC: last step, messages, final (0/1), producer."""
RAW = ".raw"
"""The raw twin of a channel: ``<channel>.raw`` (its own key: the participant's handshake
would take raw messages on its own keys as bad ones)."""
RAW_RECORDS = "rawrecords"

# the Chapter 6 corner's fields (the run's journal at step 100): the plant's state and
# response are 1-element arrays, as the model gives them, its arm loads floats
_ONE = np.array([0.1])
STATE = {f: _ONE for f in ("z_b", "v_b", "z_w", "v_w", "z_damper", "v_damper", "arm_angle")}
RESPONSE = {f: _ONE for f in (
    "a_b", "a_w", "F_t", "F_d", "F_s", "F_bs",
    *(f"a_arm_{p}_{a}" for p in ("loc1", "cg", "loc2") for a in "xyz"))}
ARM = {f"{j}_{a}": 123.456789 for j in ("ball_joint", "damper_mount", "bush_front",
                                        "bush_rear") for a in "xyz"}
ARM.update(bump_stop_y=-1.5, bump_stop_z=-2.5, torsion_bar_mx=-1663.2)
FORCE = {"tyre_road": {"F_t": _ONE, "k_t": _ONE, "z_g": _ONE},
         "controller": {"F_d": _ONE, "c_eff": _ONE}}


def _sizes(key_bytes: bytes) -> dict[str, int]:
    """Bytes of each signed message of the protocol (the raw messages are this long)."""
    from cosim.auth import RunKey
    from cosim.wire import encode

    auth = RunKey(key_bytes)
    one: dict[str, dict[str, Any]] = {"state": STATE, "response": RESPONSE, "arm": ARM, **FORCE}
    out = {c: len(auth.sign("k", encode("data", 100, 0.05, d))) for c, d in one.items()}
    return out


def _orchestrator_defaults() -> tuple[float, Any]:
    """(the polling of a pinned node [us], the link lease of a stall timeout) as the
    orchestrator sets them for its local nodes."""
    try:
        from orchestrator.local_nodes import PINNED_SPIN_US, local_lease_ms
    except ImportError:  # before the local nodes had a module of their own
        from orchestrator.runner import PINNED_SPIN_US, local_lease_ms  # type: ignore
    return float(PINNED_SPIN_US), local_lease_ms


# ---- null chain: node side ------------------------------------------------------------------
class RawOut:
    """The raw twin of a participant's outputs: unsigned puts of fixed-size bytes on
    ``<channel>.raw``, and the records batches (64 messages or 50 ms) on ``<node>/rawrecords``."""

    def __init__(self, bus: Any, run: str, node: str, channels: dict[str, int]) -> None:
        self.who = ROLES.index(node)
        self.pubs = {c: bus.publisher(keys.key(run, node, c + RAW)) for c in channels}
        self.pad = {c: b"\0" * max(0, n - len(MAGIC) - _K.size) for c, n in channels.items()}
        self.rec = bus.publisher(keys.key(run, node, RAW_RECORDS))
        self.batch: list[bytes] = []
        self.k_last = -1
        self.since = time.monotonic()

    def put(self, channel: str, k: int, extra: int = 0) -> None:
        """One raw message of ``channel``'s size plus ``extra`` bytes (the raw twin of a
        step message carrying other channels' messages too)."""
        raw = MAGIC + _K.pack(k) + self.pad[channel] + b"\0" * extra
        self.pubs[channel](raw)
        if sum(map(len, self.batch)) + len(raw) > 47 * 1024:  # as RecordBatch: one Zenoh
            self.flush(self.k_last)  # batch (64 KiB) carries it, or the low-latency link
        self.batch.append(raw)  # drops it
        self.k_last = k
        if len(self.batch) >= 64 or time.monotonic() - self.since >= 0.05:
            self.flush(k)

    def flush(self, k: int, final: bool = False) -> None:
        self.since = time.monotonic()
        if self.batch or final:
            head = MAGIC + _BATCH.pack(k, len(self.batch), int(final), self.who)
            self.rec(head + b"".join(self.batch))
            self.batch = []


def busy(us: float) -> None:
    """Spend ``us`` of this thread's CPU [us] (a stand-in for model work: CPU time, so a
    preempted node still does all of it)."""
    if us > 0.0:
        end = time.thread_time() + us * 1e-6
        while time.thread_time() < end:
            pass


def raw_wait(feed: Any, have: list[int], need: int, spin_s: float) -> None:
    """Until a raw message of step >= ``need`` has come on ``feed`` (``have[0]``: the latest
    step seen), polling ``spin_s`` before blocking as :meth:`Participant.wait` does."""
    while have[0] < need:
        end = time.perf_counter() + spin_s
        while (raw := feed.try_recv()) is None and time.perf_counter() < end:
            os.sched_yield()
        if raw is None:
            raw = feed.recv()
        have[0] = max(have[0], _K.unpack_from(raw, len(MAGIC))[0])


def raw_feed(part: Any, node: str, channel: str) -> tuple[Any, list[int]]:
    """The raw twin of a stepped input, and the latest step seen on it. Declared before the
    participant's own input: the handshake's proof that the participant's path is live then
    proves this one too (Zenoh sends a session's declarations in order on each link)."""
    return part.bus.feed(keys.key(part.run, node, channel + RAW), 1024), [-1]


def plant(part: Any, cmd: dict) -> None:
    force_nodes = [n for n in FORCE_NODES if n in cmd["nodes"]]
    raw = cmd["wire"] == "raw"
    feeds = [raw_feed(part, n, "force") for n in force_nodes] if raw else []
    for c in ("state", "response", "arm"):
        part.output(c)
    tags = [part.listen(n, "force") for n in force_nodes]
    if raw:
        out = RawOut(part.bus, part.run, part.node,
                     {c: cmd["sizes"][c] for c in ("state", "response", "arm")})
    n = int(part.handshake(info={}, timeout_s=STALL_S)["n_steps"])
    work = float(cmd["work"].get(part.node, 0.0))
    CPU[:] = [time.process_time()]
    later: list[tuple[str, int, float, Any]] = []
    for k in range(n + 1):
        t = k * H
        if raw:  # one message a step, as the protocol's step message (#28 item 2)
            out.put("state", k, sum(cmd["sizes"][c] for c, *_ in later))
            for feed, have in feeds:
                raw_wait(feed, have, k, part.spin_s)
            busy(work)
        else:  # as the plant: last step's response and loads encoded while it waits,
            part.publish("state", k, t, STATE)  # in the next step's message
            part.send()
            for c, kk, tt, d in later:
                part.publish(c, kk, tt, d, hold=True)
            part.wait({tag: k for tag in tags})
            busy(work)  # the model's substeps, before the next state
        later = [("response", k, t, RESPONSE), ("arm", k, t, ARM)]
        part.progress(k, t)
    for c, kk, tt, d in later:
        if not raw:
            part.publish(c, kk, tt, d)
    if raw:
        out.put("response", n, cmd["sizes"]["arm"])
        out.flush(n, final=True)
    CPU.append(time.process_time())
    part.finish(n, n * H)


def force_node(part: Any, cmd: dict) -> None:
    name = part.node
    lag = 0 if cmd["exchange"] == "sequential" else 1
    raw = cmd["wire"] == "raw"
    if raw:
        feed, have = raw_feed(part, "plant", "state")
        out = RawOut(part.bus, part.run, name, {"force": cmd["sizes"][name]})
    part.output("force")
    state = part.listen("plant", "state", required=("z_w",))
    n = int(part.handshake(timeout_s=STALL_S)["n_steps"])
    work = float(cmd["work"].get(name, 0.0))
    CPU[:] = [time.process_time()]
    for k in range(n + 1):
        t = k * H
        if raw:
            raw_wait(feed, have, max(k - lag, 0), part.spin_s)
            busy(work)
            out.put("force", k)
        else:
            part.wait({state: max(k - lag, 0)})
            busy(work)  # the law, the road and the tyre
            part.publish("force", k, t, FORCE[name])
        part.progress(k, t)
    if raw:
        out.flush(n, final=True)
    CPU.append(time.process_time())
    part.finish(n, n * H)


def _raw_inbox(bus: Any, keyexpr: str) -> Any:
    import queue

    q: queue.SimpleQueue = queue.SimpleQueue()
    bus.subscribe(keyexpr, lambda _k, raw: q.put(raw))
    return q


def recorder(part: Any, cmd: dict) -> None:
    """Takes every producer's records batches (each message in them decoded, in the protocol
    way); done once every producer's last batch has come."""
    from cosim.listener import Listener
    from cosim.wire import decode

    producers = [n for n in cmd["nodes"] if n in ("plant", *FORCE_NODES)]
    raw = cmd["wire"] == "raw"
    inbox = _raw_inbox(part.bus, keys.key(part.run, "*", RAW_RECORDS))
    listener = Listener(part, STALL_S)
    for node in producers:
        listener.feed(node, "records", kinds=("records",))
    ended: set[str] = set()
    CPU[:] = []
    work = float(cmd["work"].get(part.node, 0.0))
    per_step = 3 + len(producers) - 1  # messages a step: the plant's 3, one per force node
    while len(ended) < len(producers):
        if listener.start is not None and not CPU:
            CPU.append(time.process_time())
        if listener.start is None or not raw:
            rec = listener.poll(timeout=0.05)
            if rec is None:
                continue
            for _channel, one in rec.msg.d["records"]:
                decode(one)
            node, k, final, count = rec.node, rec.msg.k, False, len(rec.msg.d["records"])
        else:
            got = inbox.get(timeout=STALL_S)
            k, count, final, who = _BATCH.unpack_from(got, len(MAGIC))
            node = ROLES[who]
        busy(work * count / per_step)  # journal, checks
        if final or k >= int(cmd["n"]):  # the start's (it may come after a first batch)
            ended.add(node)
    n = int(cmd["n"])
    CPU.append(time.process_time())
    part.finish(n, n * H)


def fatigue(part: Any, cmd: dict) -> None:
    """Takes the plant's records batches (verified, its arm messages decoded, in the protocol
    way: the live fatigue node since #28 item 4), nothing else; done with the last step."""
    from cosim.listener import Listener
    from cosim.wire import codec

    raw = cmd["wire"] == "raw"
    arm = codec("plant/arm")
    inbox = _raw_inbox(part.bus, keys.key(part.run, "plant", RAW_RECORDS))
    listener = Listener(part, STALL_S)
    listener.feed("plant", "records", kinds=("records",))
    k = -1
    CPU[:] = []
    work = float(cmd["work"].get(part.node, 0.0))
    while listener.start is None or k < int(listener.start["n_steps"]):
        k_before = k
        if listener.start is not None and not CPU:
            CPU.append(time.process_time())
        if listener.start is None or not raw:
            rec = listener.poll(timeout=0.05)
            if rec is not None:
                for channel, one in rec.msg.d["records"]:
                    if channel == "arm":
                        k = arm.decode(one).k
        else:
            k = _BATCH.unpack_from(inbox.get(timeout=STALL_S), len(MAGIC))[0]
        busy(work * max(0, k - k_before))  # stresses, counting, damage of the block
    n = int(listener.start["n_steps"])
    CPU.append(time.process_time())
    part.finish(n, n * H)


def node_main(name: str, connect: list[str], spin_us: float, listen: str | None = None
              ) -> int:
    """A node process: one trial per command line on stdin, its result on stdout."""
    from cosim.auth import RunKey
    from cosim.bus import ZenohBus, zenoh_config
    from cosim.participant import Participant

    _, local_lease_ms = _orchestrator_defaults()

    if name == "fatigue":
        os.nice(10)
    # as a run's local node: in the explicit mesh (listen on its socket, gossip off)
    bus = ZenohBus(zenoh_config(connect, [listen] if listen else None, lowlatency=True,
                                lease_ms=local_lease_ms(STALL_S), mode="peer",
                                gossip=listen is None))
    role = {"plant": plant, "tyre_road": force_node, "controller": force_node,
            "recorder": recorder, "fatigue": fatigue}[name]
    print("up", flush=True)
    for line in sys.stdin:
        cmd = json.loads(line)
        if cmd.get("quit"):
            break
        auth = None if cmd["wire"] == "unsigned" else RunKey(bytes.fromhex(cmd["key"]))
        part = Participant(bus, cmd["run"], name, stall_timeout_s=STALL_S,
                           spin_s=spin_us * 1e-6, auth=auth)
        part.expect_start = {"n_steps": cmd["n"], "h": H, "nodes": cmd["nodes"]}
        try:
            role(part, cmd)
        finally:
            part.close()
        print(json.dumps({"cpu_s": CPU[-1] - CPU[0]}), flush=True)
    bus.close()
    return 0


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
        from orchestrator.placement import background, core_layout, usable_cores
        from orchestrator.placement import pin as pin_to

        spin_us, _ = _orchestrator_defaults()

        self.names = list(ROLES[:count])
        cores = core_layout(self.names, usable_cores()) if pin else {}
        self.procs: dict[str, subprocess.Popen] = {}
        self.cores: dict[str, int] = {}
        for name in self.names:
            spin = spin_us if name in cores else 0
            links = [a for ep in mesh.connect(name) for a in ("--connect", ep)]
            self.procs[name] = p = subprocess.Popen(
                [*NODE_CMD, name, *links, "--listen", mesh.listen(name),
                 "--spin-us", str(spin)], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                text=True, cwd=ROOT, env=dict(os.environ, PYTHONPATH=str(ROOT)))
            if name in cores and pin_to(p.pid, cores[name]):
                self.cores[name] = cores[name]
        for name, p in self.procs.items():
            line = _line(p)
            if line != "up":
                raise RuntimeError(f"null node {name} did not start ({line!r})")
        from cosim import node_kinds as nk
        for name in self.cores:  # as a run does once it has started
            if nk.off_critical_path(name):
                background(self.procs[name].pid)
        self.bus = bus

    def trial(self, i: int, n: int, exchange: str, wire: str,
              work: dict[str, float] | None = None) -> dict[str, Any]:
        """One run of ``n`` steps: steps/s (``n / step_wall_s``) and each node's CPU per step."""
        from cosim.auth import RunKey
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
    from orchestrator.placement import should_pin, usable_cores

    _, local_lease_ms = _orchestrator_defaults()

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


# ---- wire -----------------------------------------------------------------------------------
def msgpack_checked(node: str, channel: str) -> Callable[[bytes], dict[str, Any]]:
    """The alternative to :class:`cosim.wire.ChannelCodec`: msgpack, then the same checks in
    Python. Raises :class:`WireError` as the codec does."""
    spec = schema.channel(node, channel)
    assert spec is not None, f"{node}/{channel} is not in the schema"
    limit, declared = spec.limit, tuple(f.name for f in spec.fields)
    nonneg = schema.nonneg_fields(node, channel)

    def finite(x: Any) -> bool:
        return isinstance(x, (int, float)) and not isinstance(x, bool) and -limit <= x <= limit

    def check(raw: bytes) -> dict[str, Any]:
        m = msgpack.unpackb(raw)
        if not isinstance(m, dict) or m.get("v") != SCHEMA_VERSION or m.get("kind") != "data":
            raise WireError("not a data message of this version")
        k, t, d = m.get("k"), m.get("t"), m.get("d")
        if not isinstance(k, int) or k < 0 or not isinstance(t, float) or not t >= 0 \
                or not isinstance(d, dict):
            raise WireError("bad k, t or payload")
        for name in declared:
            if name in d:
                v = d[name]
                if not all(finite(x) for x in (v if isinstance(v, list) else (v,))):
                    raise WireError(f"field {name!r} out of bounds")
                if name in nonneg and min(v if isinstance(v, list) else (v,)) < 0:
                    raise WireError(f"field {name!r} negative")
        return d

    return check


def _us(fn: Callable[[], Any], n: int) -> float:
    return statistics.median(timeit.repeat(fn, number=n, repeat=5)) / n * 1e6


def wire(args: argparse.Namespace) -> int:
    """``wire``: the codec, signing and a coupled step's protocol work [us per call]."""
    n = args.n
    key = RunKey(os.urandom(32), os.urandom(16))
    st, rs, ar = (encode("data", 5, 0.005, d) for d in (STATE, RESPONSE, ARM))
    force = {name: encode("data", 5, 0.005, d) for name, d in FORCE.items()}
    plant_kx = "suscosim/run/plant/step"
    sign_plant = key.signer(plant_kx)
    plant_step = sign_plant(encode_step(5, 0.005, [("response", rs), ("arm", ar), ("state", st)]))
    force_kx = {name: f"suscosim/run/{name}/step" for name in FORCE}
    signers = {name: key.signer(kx) for name, kx in force_kx.items()}
    force_steps = {name: signers[name](encode_step(5, 0.005, [("force", force[name])]))
                   for name in FORCE}

    print(f"per call, us (median of 5 rounds of {n}); Python {sys.version.split()[0]}\n")
    print("| message | encode (msgspec) | decode + checks (msgspec, C) | "
          "decode + checks (msgpack, Python) |")
    print("|---|---|---|---|")
    for chan, data, raw in (("state", STATE, st), ("arm", ARM, ar)):
        ours, theirs = codec(f"plant/{chan}"), msgpack_checked("plant", chan)
        assert ours.decode(raw).d == theirs(raw)  # the two agree on what they accept
        print(f"| plant/{chan} ({len(data)} fields, {len(raw)} B) "
              f"| {_us(lambda d=data: encode('data', 5, 0.005, d), n):.2f} "
              f"| {_us(lambda c=ours, r=raw: c.decode(r), n):.2f} "
              f"| {_us(lambda c=theirs, r=raw: c(r), n):.2f} |")
    bad = encode("data", 5, 0.005, {**STATE, "z_w": math.nan})  # both must refuse it
    for check in (codec("plant/state").decode, msgpack_checked("plant", "state")):
        try:
            check(bad)
        except WireError:
            continue
        raise SystemExit(f"{check} took a NaN: the comparison is not like for like")

    print(f"\n| signing (the plant's step, {len(plant_step)} B) | us |\n|---|---|")
    body = encode_step(5, 0.005, [("response", rs), ("arm", ar), ("state", st)])
    print(f"| sign | {_us(lambda: sign_plant(body), n):.2f} |")
    print(f"| verify | {_us(lambda: key.verify(plant_kx, plant_step), n):.2f} |")

    def plant_step_work() -> None:
        for chan, data in (("state", STATE), ("response", RESPONSE), ("arm", ARM)):
            codec(f"plant/{chan}").decode(encode("data", 5, 0.005, data))
        sign_plant(encode_step(5, 0.005, [("response", rs), ("arm", ar), ("state", st)]))
        for name, raw in force_steps.items():
            for chan, one in inner(decode(key.verify(force_kx[name], raw))):
                codec(f"{name}/{chan}").decode(one)

    def force_step_work() -> None:
        for chan, one in inner(decode(key.verify(plant_kx, plant_step))):
            if chan == "state":
                codec("plant/state").decode(one)
        raw = encode("data", 5, 0.005, FORCE["tyre_road"])
        codec("tyre_road/force").decode(raw)
        signers["tyre_road"](encode_step(5, 0.005, [("force", raw)]))

    print("\n| a coupled step's protocol work, warm, without the bus | us |\n|---|---|")
    print(f"| plant | {_us(plant_step_work, n):.2f} |")
    print(f"| force node (tyre_road) | {_us(force_step_work, n):.2f} |")
    return 0


# ---- auth -----------------------------------------------------------------------------------
AUTH_SCENARIO = "scenarios/ch3_step_quarter_car.toml"


def per_message(n: int = 200_000) -> dict[str, float]:
    """Sign, verify, encode and decode of one quarter-car state message [us each]."""
    # (ROOT is on sys.path)
    from cosim.auth import RunKey, derive_run_key
    from cosim.wire import decode, encode

    key = RunKey(derive_run_key(b"bench" * 8, "bench"))
    where = "suscosim/bench/plant/state"
    body = encode("data", 1234, 1.234, {"z_b": 0.01, "v_b": 0.1, "z_w": 0.02, "v_w": 0.2})
    sign = key.signer(where)
    raw = sign(body)
    us = {name: 1e6 * min(timeit.repeat(fn, number=n, repeat=3)) / n for name, fn in (
        ("sign", lambda: sign(body)), ("verify", lambda: key.verify(where, raw)),
        ("encode", lambda: encode("data", 1234, 1.234, {"z_b": 0.01, "v_b": 0.1,
                                                        "z_w": 0.02, "v_w": 0.2})),
        ("decode", lambda: decode(body)))}
    us["bytes"] = float(len(body))
    return us


NO_AUTH = '''

class RunKey:  # bench/protocol.py auth: the same code without signing or verifying
    def __init__(self, key: bytes) -> None:
        self.key = key

    def sign(self, keyexpr: str, body: bytes) -> bytes:
        return body

    def signer(self, keyexpr: str):
        return lambda body: body

    def verify(self, keyexpr: str, raw: bytes) -> bytes:
        return raw
'''


def tree(rev: str, into: Path, auth: bool) -> Path:
    """``git archive REV`` unpacked under ``into``; without ``auth`` RunKey does nothing."""
    blob = subprocess.run(["git", "-C", str(ROOT), "archive", rev], check=True,
                          capture_output=True).stdout
    with tarfile.open(fileobj=BytesIO(blob)) as tar:
        tar.extractall(into, filter="data")
    if not auth:
        with open(into / "cosim" / "auth.py", "a") as f:
            f.write(NO_AUTH)
    return into


def one_run(tree: Path, out: Path, t_end: float) -> float:
    """Coupled steps/s of one distributed run of the Chapter 3 scenario from ``tree``."""
    env = {"PYTHONPATH": str(tree), "PATH": "/usr/bin:/bin", "HOME": str(Path.home())}
    res = subprocess.run([sys.executable, "-m", "orchestrator", "run", AUTH_SCENARIO, "--quiet",
                          "--out", str(out), "--set", f"run.t_end={t_end}"],
                         cwd=tree, env=env, capture_output=True, text=True, timeout=600)
    if res.returncode != 0:
        kept = Path(tempfile.mkdtemp(prefix="bench_auth_failed_"))
        subprocess.run(["cp", "-r", str(out), str(kept)], check=False)
        print(f"run failed in {tree} (folder kept in {kept}): {res.stderr.strip()}")
        return float("nan")
    return float(json.loads((out / "summary.json").read_text())["steps_per_s"])


def auth(args: argparse.Namespace) -> int:
    """``auth``: sign/verify per message, and steps/s with and without authentication."""
    us = per_message()
    print(f"per message ({us['bytes']:.0f} B + 20 B signature field): "
          f"sign {us['sign']:.2f} us, "
          f"verify {us['verify']:.2f} us; encode {us['encode']:.2f} us, "
          f"decode {us['decode']:.2f} us")
    with tempfile.TemporaryDirectory() as tmp:
        with_auth = tree(args.rev, Path(tmp) / "auth", True)
        without = tree(args.rev, Path(tmp) / "noauth", False)
        rows = []
        for i in range(args.pairs):
            if i % 2:  # alternate which goes first: a pair's first run must not bias it
                b = one_run(without, Path(tmp) / f"b{i}", args.t_end)
                a = one_run(with_auth, Path(tmp) / f"a{i}", args.t_end)
            else:
                a = one_run(with_auth, Path(tmp) / f"a{i}", args.t_end)
                b = one_run(without, Path(tmp) / f"b{i}", args.t_end)
            print(f"pair {i + 1}: authenticated {a:7.0f} steps/s, without {b:7.0f} steps/s, "
                  f"ratio {a / b:.3f}", flush=True)
            if a == a and b == b:  # neither failed
                rows.append((a, b))
    if not rows:
        return 1
    ratios = [a / b for a, b in rows]
    print(f"median: authenticated {statistics.median(a for a, _ in rows):.0f} steps/s, "
          f"without {statistics.median(b for _, b in rows):.0f} steps/s, "
          f"ratio {statistics.median(ratios):.3f} (min {min(ratios):.3f}, "
          f"max {max(ratios):.3f})")
    return 0


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
    p = sub.add_parser("wire", help="the codec, signing and a step's protocol work [us]")
    p.add_argument("--n", type=int, default=20000, help="calls per timeit round")
    p.set_defaults(fn=wire)
    p = sub.add_parser("auth", help="message authentication: per message and per run")
    p.add_argument("--pairs", type=int, default=5)
    p.add_argument("--rev", default="HEAD", help="the revision to measure")
    p.add_argument("--t-end", type=float, default=4.0, help="simulated time [s]")
    p.set_defaults(fn=auth)
    args = ap.parse_args(argv)
    return int(args.fn(args) or 0)


if __name__ == "__main__":
    raise SystemExit(main())
