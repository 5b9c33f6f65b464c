"""The floor of the architecture: the lock-step message pattern of a coupled step with ZERO
model work, in the same processes over real Zenoh, against the bare round trip (issue #16).

    python bench/bench_null_chain.py [--steps 2000] [--repeats 3] [--counts 2,3,4,5]

The nodes are the run's (plant, tyre_road, controller, recorder, fatigue: the first 2, 3, 4
or 5), each its own process started as the orchestrator starts them: a Zenoh peer session
with the nodes' options (``cosim.bus.zenoh_config``: loopback, low-latency transport, link
lease of a 30 s stall timeout), pinned to the core the run's placement gives it
(``orchestrator.placement``) and then polling its input for ``PINNED_SPIN_US`` before it
blocks, the fatigue node at ``nice +10``. This process is the orchestrator: the run's own
:class:`orchestrator.clock.Clock` (start barrier, progress, done; steps/s is
``n_steps / step_wall_s``, as in summary.json). Per step, as nodes/plant/node.py,
nodes/tyre_road/node.py and nodes/controller/node.py do (the order and the sizes of the
messages of the Chapter 6 double-wishbone corner):

* the plant puts ``state`` of step k, then last step's ``response`` and ``arm``, then waits
  for ``force`` of step k from each force node;
* tyre_road and the controller wait for ``state`` of step k (``sequential``) or k - 1
  (``parallel``), then put their ``force``;
* every producer sends what it published to the recorder in batches (64 messages or
  50 ms); the recorder sends the fatigue node a block of 500 steps of ``arm``.

Two ways of sending, both with no model work at all:

* ``protocol``: the run's code: :class:`cosim.participant.Participant` (publish: encode, sign;
  wait: verify, decode, mailbox; records batches), :class:`cosim.listener.Listener` for the
  recorder and the fatigue node (each message verified and decoded), constant payloads;
* ``unsigned`` (``--wires``): the protocol without the run key (nothing signed or verified);
* ``raw``: bytes of the same sizes put and taken directly on the same Zenoh sessions (keys
  ``<channel>.raw``; a step number in the first bytes, nothing encoded or checked): what
  Zenoh and the processes alone cost. The start barrier and the end are the participant's
  in both.

The bare round trip is bench/bench_zenoh_pingpong.py's, run in the same bench: the
configuration of bench/bench_workloads.py (callback subscriber, low-latency transport,
express publishers; its rate is what issue #16's ratio bars are measured against) and the
nodes' own (FIFO subscriber, pinned to the two cores, polling before blocking).
Each configuration is run ``--repeats`` times, interleaved; median and range are printed,
with the load average (``/proc/loadavg``) at each configuration.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import struct
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import numpy as np  # noqa: E402

from cosim import keys  # noqa: E402

ROLES = ("plant", "tyre_road", "controller", "recorder", "fatigue")
FORCE_NODES = ("tyre_road", "controller")
WIRES = ("raw", "protocol", "unsigned")
EXCHANGES = ("sequential", "parallel")
H = 0.0005
"""The Chapter 6 step [s] (only the start's plausibility check and t = k h use it)."""
STALL_S = 30.0
BLOCK_STEPS = 500
"""Steps of ``arm`` per load block to the fatigue node (``fatigue.block_samples``)."""
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
RAW_LOADS = "rawloads"

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
LOAD_BLOCK = {"k0": 0, "t": [0.1] * BLOCK_STEPS, **{f: [123.456789] * BLOCK_STEPS for f in ARM}}


def _sizes(key_bytes: bytes) -> dict[str, int]:
    """Bytes of each signed message of the protocol (the raw messages are this long)."""
    from cosim.auth import RunKey
    from cosim.wire import encode

    auth = RunKey(key_bytes)
    one: dict[str, dict[str, Any]] = {"state": STATE, "response": RESPONSE, "arm": ARM, **FORCE}
    out = {c: len(auth.sign("k", encode("data", 100, 0.05, d))) for c, d in one.items()}
    for i, piece in enumerate(_pieces()):
        out[f"loads{i}"] = len(auth.sign("k", encode("data", 499, 0.25, piece)))
    return out


def _pieces() -> list[dict[str, Any]]:
    """A load block as the recorder sends it: cut into pieces that fit one message (Zenoh's
    low-latency transport does not fragment)."""
    from nodes.recorder.node import wire_pieces

    return wire_pieces(LOAD_BLOCK)


def _orchestrator_defaults() -> tuple[float, Any]:
    """(the polling of a pinned node [us], the link lease of a stall timeout) as the
    orchestrator sets them for its local nodes."""
    try:
        from orchestrator.local_nodes import PINNED_SPIN_US, local_lease_ms
    except ImportError:  # before the local nodes had a module of their own
        from orchestrator.runner import PINNED_SPIN_US, local_lease_ms  # type: ignore
    return float(PINNED_SPIN_US), local_lease_ms


# ---- node side ------------------------------------------------------------------------------
class RawOut:
    """The raw twin of a participant's outputs: unsigned puts of fixed-size bytes on
    ``<channel>.raw``, and the records batches (64 messages or 50 ms) on ``<node>/rawrecords``."""

    def __init__(self, bus: Any, run: str, node: str, channels: dict[str, int]) -> None:
        self.who = ROLES.index(node)
        self.pubs = {c: bus.publisher(keys.key(run, node, c + RAW)) for c in channels}
        self.pad = {c: b"\0" * max(0, n - len(MAGIC) - _K.size) for c, n in channels.items()}
        self.rec = bus.publisher(keys.key(run, node, RAW_RECORDS))
        self.batch: list[bytes] = []
        self.since = time.monotonic()

    def put(self, channel: str, k: int) -> None:
        raw = MAGIC + _K.pack(k) + self.pad[channel]
        self.pubs[channel](raw)
        self.batch.append(raw)
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
        if raw:
            out.put("state", k)
            for c, kk, _, _ in later:
                out.put(c, kk)
            for feed, have in feeds:
                raw_wait(feed, have, k, part.spin_s)
            busy(work)
        else:
            part.publish("state", k, t, STATE)
            for c, kk, tt, d in later:
                part.publish(c, kk, tt, d)
            part.wait({tag: k for tag in tags})
            busy(work)  # the model's substeps, before the next state
        later = [("response", k, t, RESPONSE), ("arm", k, t, ARM)]
        part.progress(k, t)
    for c, kk, tt, d in later:
        if raw:
            out.put(c, kk)
        else:
            part.publish(c, kk, tt, d)
    if raw:
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
    way); a load block to the fatigue node every ``BLOCK_STEPS`` steps of the plant and the
    rest at the end; done once every producer's last batch has come."""
    from cosim.listener import Listener
    from cosim.wire import decode

    producers = [n for n in cmd["nodes"] if n in ("plant", *FORCE_NODES)]
    to_fatigue = "fatigue" in cmd["nodes"]
    raw = cmd["wire"] == "raw"
    if to_fatigue:
        part.output("loads")
    inbox = _raw_inbox(part.bus, keys.key(part.run, "*", RAW_RECORDS))
    loads = part.bus.publisher(keys.key(part.run, part.node, RAW_LOADS))
    pieces = _pieces()
    pads = [b"\0" * cmd["sizes"][f"loads{i}"] for i in range(len(pieces))]
    listener = Listener(part, STALL_S)
    for node in producers:
        listener.feed(node, "records", kinds=("records",))
    ended: set[str] = set()
    CPU[:] = []
    work = float(cmd["work"].get(part.node, 0.0))
    per_step = 3 + len(producers) - 1  # messages a step: the plant's 3, one per force node
    sent = 0  # steps of arm sent to the fatigue node
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
        busy(work * count / per_step)  # journal, checks, load streaming
        n = int(cmd["n"])  # the start's (it may come after a first batch)
        if final or k >= n:
            ended.add(node)
        while to_fatigue and node == "plant" and (sent + BLOCK_STEPS - 1 <= k
                                                  or (k >= n and sent <= n)):
            k_last = min(sent + BLOCK_STEPS - 1, n)
            for i, (piece, pad) in enumerate(zip(pieces, pads, strict=True)):
                kp = k_last if i == len(pieces) - 1 else k_last - 1
                if raw:
                    loads(MAGIC + _K.pack(kp) + pad)
                else:
                    part.publish("loads", kp, kp * H, piece, record=False)
            sent = k_last + 1
    n = int(cmd["n"])
    CPU.append(time.process_time())
    part.finish(n, n * H)


def fatigue(part: Any, cmd: dict) -> None:
    """Takes the load blocks (verified and decoded in the protocol way), nothing else; done
    with the block of the last step."""
    from cosim.listener import Listener

    raw = cmd["wire"] == "raw"
    inbox = _raw_inbox(part.bus, keys.key(part.run, "recorder", RAW_LOADS))
    listener = Listener(part, STALL_S)
    listener.feed("recorder", "loads", required=("k0", "t"))
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
                k = rec.msg.k
        else:
            k = _K.unpack_from(inbox.get(timeout=STALL_S), len(MAGIC))[0]
        busy(work * max(0, k - k_before))  # stresses, counting, damage of the block
    n = int(listener.start["n_steps"])
    CPU.append(time.process_time())
    part.finish(n, n * H)


def node_main(name: str, connect: str, spin_us: float) -> int:
    """A node process: one trial per command line on stdin, its result on stdout."""
    from cosim.auth import RunKey
    from cosim.bus import ZenohBus, zenoh_config
    from cosim.participant import Participant

    _, local_lease_ms = _orchestrator_defaults()

    if name == "fatigue":
        os.nice(10)
    bus = ZenohBus(zenoh_config([connect], lowlatency=True, lease_ms=local_lease_ms(STALL_S),
                                mode="peer"))
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
# ---- orchestrator side ----------------------------------------------------------------------
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

    def __init__(self, bus: Any, endpoint: str, count: int, pin: bool) -> None:
        from orchestrator.placement import core_layout, usable_cores
        from orchestrator.placement import pin as pin_to

        spin_us, _ = _orchestrator_defaults()

        self.names = list(ROLES[:count])
        cores = core_layout(self.names, usable_cores()) if pin else {}
        self.procs: dict[str, subprocess.Popen] = {}
        self.cores: dict[str, int] = {}
        for name in self.names:
            spin = spin_us if name in cores else 0
            self.procs[name] = p = subprocess.Popen(
                [sys.executable, __file__, "--node", name, "--connect", endpoint,
                 "--spin-us", str(spin)], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                text=True, env=dict(os.environ, PYTHONPATH=str(ROOT)))
            if name in cores and pin_to(p.pid, cores[name]):
                self.cores[name] = cores[name]
        for name, p in self.procs.items():
            line = _line(p)
            if line != "up":
                raise RuntimeError(f"null node {name} did not start ({line!r})")
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
    from bench_zenoh_pingpong import one

    out: dict[str, list[float]] = {"callback": [], "nodes": []}
    for _ in range(repeats):
        out["callback"].append(1e6 / one(n, fifo=False, ll=True, express=True)["rtt_us"])
        out["nodes"].append(1e6 / one(n, fifo=True, ll=True, express=True, pinned=True)["rtt_us"])
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=2000, help="coupled steps per run")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--counts", default="2,3,4,5", help="process counts, of 2..5")
    ap.add_argument("--wires", default="raw,protocol",
                    help="of raw, protocol, unsigned (the protocol without the run key)")
    ap.add_argument("--exchanges", default="sequential,parallel")
    ap.add_argument("--pin", choices=("auto", "off"), default="auto",
                    help="auto: pinned as the orchestrator pins (2-4 cores), off: not pinned")
    ap.add_argument("--pingpong-n", type=int, default=2000)
    ap.add_argument("--work", default="",
                    help="CPU of model work per coupled step [us] by node, e.g. plant=145,"
                         "tyre_road=35 (default none: the null chain); spent after a node's "
                         "inputs came (plant, force nodes), per records batch (recorder) or "
                         "per load block (fatigue), in proportion to the steps covered")
    ap.add_argument("--node", help=argparse.SUPPRESS)
    ap.add_argument("--connect", help=argparse.SUPPRESS)
    ap.add_argument("--spin-us", type=float, default=0.0, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.node:
        return node_main(args.node, args.connect, args.spin_us)

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
    endpoint = free_loopback_endpoint()
    bus = ZenohBus(zenoh_config(listen=[endpoint], lowlatency=True,
                                lease_ms=local_lease_ms(STALL_S)))
    rows = []
    try:
        for count in counts:
            chain = Chain(bus, endpoint, count, pin)
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


if __name__ == "__main__":
    raise SystemExit(main())
