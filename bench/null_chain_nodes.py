"""The null chain's node processes and the Chapter 6 corner's payload sizes they send
(``python -m bench null-chain`` starts them as ``python -m bench.null_chain nodes NAME``;
bench/null_chain.py says what is measured). ``bench/protocol.py``'s wire costs use the same
payloads."""

from __future__ import annotations

import json
import os
import struct
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from cosim import keys  # noqa: E402
from cosim.auth import RunKey  # noqa: E402
from cosim.wire import codec, decode, encode  # noqa: E402

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

    auth = RunKey(key_bytes)
    one: dict[str, dict[str, Any]] = {"state": STATE, "response": RESPONSE, "arm": ARM, **FORCE}
    out = {c: len(auth.sign("k", encode("data", 100, 0.05, d))) for c, d in one.items()}
    return out


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
            os.sched_yield()  # as the plant node: a force node on its core first
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
    from cosim.bus import ZenohBus, zenoh_config
    from cosim.participant import Participant
    from orchestrator.local_nodes import local_lease_ms

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


