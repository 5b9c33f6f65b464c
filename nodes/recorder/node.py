"""The recorder node: every data channel of a run into the journal, then the run's table.

It subscribes to the records feed of every producer node of the run
(``suscosim/<run>/<node>/records``: the node's data messages exactly as it published them, in
batches of a few steps), appends each valid data message to the append-only journal as it
arrives, and once every channel has
delivered every step 0..N, exports ``table.csv`` / ``table.parquet`` and reports per-channel
statistics to the orchestrator. On an abort it flushes, exports what is complete, and stops.

When the run has a live fatigue node, the recorder also streams the load channel
(``plant/arm``) to it as blocks on ``recorder/loads`` (see cosim.channels): steps in order,
no gaps, ``fatigue.block_samples`` steps per block, the last block at the end of the run.

A batch must be signed with the run's key (:meth:`Participant.open`); each data message in
it must decode and keep the shape of its channel (:class:`ChannelShapes`: a field is a number
or a list of one length, as in the channel's first message). Anything else is rejected and
counted, never journaled: one ragged batch cannot make a complete journal unexportable.
"""

from __future__ import annotations

import queue
import threading
import time
from pathlib import Path
from typing import Any

from cosim import channels as ch
from cosim import keys
from cosim import node_kinds as nk
from cosim.errors import RunError, WireError
from cosim.journal import JournalWriter, read_journal
from cosim.listener import Listener, Received
from cosim.load_blocks import LoadStreamer, wire_pieces
from cosim.participant import Participant
from cosim.table import build_table, channel_stats, export
from cosim.wire import decode

FLUSH_PERIOD_S = 0.05


class ChannelShapes:
    """The shape of each field of each channel (None: a number; n: a list of n numbers), as
    its first data message gives it; a later message must match for the fields it shares."""

    def __init__(self) -> None:
        self.shapes: dict[str, dict[str, int | None]] = {}

    def check(self, channel: str, d: dict[str, Any]) -> str | None:
        """None if ``d`` fits the channel (the first message fixes it), else what is wrong."""
        got = {f: (len(v) if type(v) is list else None) for f, v in d.items()}
        known = self.shapes.get(channel)
        if known is None:
            self.shapes[channel] = got
            return None
        bad = [f for f, n in got.items() if f in known and known[f] != n]
        if bad:
            f = bad[0]
            return (f"field '{f}' has shape {got[f]} where the channel's first message had "
                    f"{known[f]} (None: a number)")
        for f, n in got.items():
            known.setdefault(f, n)
        return None


def finalize(journal_path: Path, folder: Path) -> dict[str, Any]:
    """Table, exports and stats from a journal on disk (also used after a crash)."""
    contents = read_journal(journal_path)
    table, bad = build_table(contents.records)
    files = export(table, folder) if len(table["t"]) else {}
    return {"stats": channel_stats(table), "files": files, "rows": int(len(table["t"])),
            "torn": contents.torn, "undecodable": bad}


class BlockSender:
    """Publishes load blocks from a thread of its own: a put to a busy fatigue node may block
    (reliable, blocking congestion control), and the recorder must go on journaling."""

    def __init__(self, part: Participant) -> None:
        self.part = part
        self.queue: queue.SimpleQueue[dict[str, Any] | None] = queue.SimpleQueue()
        self.thread = threading.Thread(target=self._loop, name="load-blocks", daemon=True)
        self.thread.start()

    def send(self, blk: dict[str, Any]) -> None:
        self.queue.put(blk)

    def _loop(self) -> None:
        while (blk := self.queue.get()) is not None:
            for piece in wire_pieces(blk):
                k_last = piece["k0"] + len(piece["t"]) - 1
                self.part.publish(ch.LOADS, k_last, piece["t"][-1], piece, record=False)

    def close(self, timeout_s: float = 60.0) -> None:
        """Let the queued blocks go out (bounded), then stop the thread."""
        self.queue.put(None)
        self.thread.join(timeout=timeout_s)


def run(part: Participant, scenario: dict[str, Any]) -> None:
    """Record the run until every channel is complete (or the run is aborted).

    Producers (the coupled kinds of the registry, :func:`cosim.node_kinds.producers`) send
    their data messages, exactly as they published them, in batches on ``<node>/records``
    (see cosim.participant); each one is validated and journaled.
    """
    run_cfg = scenario["run"]
    folder = Path(run_cfg["dir"])
    journal_path = folder / "journal.msgpack"
    journal = JournalWriter(journal_path, part.run)
    producers = [n for n in run_cfg["nodes"] if n in nk.producers() and n != part.node]
    streamer: LoadStreamer | None = None
    sender: BlockSender | None = None
    if ch.FATIGUE in run_cfg["nodes"]:
        part.output(ch.LOADS)
        block = (scenario.get("fatigue") or {}).get("block_samples", 500)
        streamer = LoadStreamer(block)
        sender = BlockSender(part)
    load_name = "/".join(ch.LOAD_CHANNEL)
    listener = Listener(part, run_cfg["start_timeout_s"])
    for node in producers:
        listener.feed(node, keys.RECORDS, kinds=("records",))
    shapes = ChannelShapes()
    expected: set[str] = set()
    got: dict[str, set[int]] = {}
    n_steps = None

    def record(node: str, channel: str, raw: bytes) -> None:
        """Validate and journal one data message of ``node/channel``."""
        try:
            msg = decode(raw)
        except WireError as exc:
            part.reject((node, channel), str(exc))
            return
        if msg.kind != "data" or msg.k < 0:
            return
        name = f"{node}/{channel}"
        if n_steps is not None and msg.k > n_steps:
            part.reject((node, channel), f"step {msg.k} after the last step {n_steps}")
            return
        wrong = shapes.check(name, msg.d)
        if wrong:
            part.reject((node, channel), f"step {msg.k}: {wrong}")
            return
        # Everything valid is journaled, duplicates included: the table keeps, per step,
        # the first message that has the channel's fields (see table.build_table).
        got.setdefault(name, set()).add(msg.k)
        journal.append(name, raw)
        if streamer is not None and sender is not None and name == load_name:
            streamer.add(msg.k, msg.t, msg.d)
            for blk in streamer.blocks(n_steps):
                sender.send(blk)

    def feed(batch: Received) -> None:
        """One ``records`` batch (verified by the listener): its data messages."""
        for channel, one in batch.msg.d["records"]:
            if not keys.NAME.match(channel):
                part.reject((batch.node, keys.RECORDS), f"bad channel name {channel!r:.40}")
                continue
            record(batch.node, channel, one)

    last_flush = last_data = time.monotonic()
    try:
        while True:
            now = time.monotonic()
            if n_steps is not None and now - last_data > part.stall_timeout_s:
                missing = sorted(c for c in expected if len(got.get(c, ())) <= n_steps)
                raise RunError(f"recorder: no data for {part.stall_timeout_s:.1f} s; "
                               f"incomplete: {', '.join(missing)}")
            if now - last_flush >= FLUSH_PERIOD_S:
                journal.flush()
                last_flush = now
            batch = listener.poll(timeout=0.05)  # the clock: raises RunError on abort
            if n_steps is None and listener.start is not None:
                n_steps = int(listener.start["n_steps"])
                for node, info in listener.start["info"].items():
                    if node not in producers:
                        continue  # e.g. the fatigue node: not a per-step channel
                    expected.update(f"{node}/{c}" for c in info.get("outputs", []))
                last_data = time.monotonic()
            if batch is None:
                continue
            feed(batch)
            last_data = time.monotonic()
            if n_steps is not None:
                done_k = min(len(got.get(c, ())) for c in expected) - 1
                part.progress(done_k, done_k * run_cfg["h"])
                if done_k >= n_steps:
                    break
    except RunError:
        for batch in listener.drain():  # the other nodes' last batches, sent as they stop
            feed(batch)
        journal.close()
        finalize(journal_path, folder)
        raise
    journal.close()
    result = _with_heartbeat(part, n_steps, n_steps * run_cfg["h"],
                             lambda: finalize(journal_path, folder),
                             min(1.0, part.stall_timeout_s / 4))
    if sender is not None:
        sender.close()
    part.finish(n_steps, n_steps * run_cfg["h"], **result)


def _with_heartbeat(part: Participant, k: int, t: float, work: Any,
                    period_s: float = 1.0) -> Any:
    """``work()`` while a thread says ``progress`` every ``period_s``: exporting the table
    (pyarrow's first import alone takes seconds on a loaded machine) is not a stall."""
    stop = threading.Event()

    def beat() -> None:
        while not stop.wait(period_s):
            part.ctl("progress", k, t, rejected=part.rejected)

    th = threading.Thread(target=beat, name="recorder-heartbeat", daemon=True)
    th.start()
    try:
        return work()
    finally:
        stop.set()
        th.join()
