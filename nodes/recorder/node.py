"""The recorder node: every data channel of a run into the journal and, as the rows complete,
into the run's table.

It subscribes to the records feed of every producer node of the run
(``suscosim/<run>/<node>/records``: the node's data messages exactly as it published them, in
batches of a few steps), appends each valid data message to the append-only journal as it
arrives (:mod:`cosim.journal`: the durable record) and gives it to the table
(:class:`cosim.table_writer.TableWriter`: ``table.csv`` / ``table.parquet`` written as rows
complete, in place when the run ends: #28 item 5, the table comes from what the recorder
holds, not from re-reading the journal). Once every channel has delivered every step 0..N it
reports per-channel statistics to the orchestrator. On an abort it flushes, puts the rows
that are complete in place, and stops. Its memory does not grow with the run (#32): the steps
each channel delivered are kept as ranges (:class:`~nodes.recorder.steps.StepSet`), the table
holds only the steps not yet complete.

As the table's rows complete, the recorder also publishes the run's coupling energy residual
per step and bond on ``recorder/coupling`` (#29 item 1; :class:`cosim.coupling_stream.
LiveResidual`, one message per :data:`LIVE_PERIOD_S` at most and at the end, signed as its
other messages): computed from the table's own rows, it is what ``summary.json``'s
``coupling_energy_residual`` sums, step by step, while the run goes. It is not journaled:
a journal's table gives it again (docs/coupling_residual.md, "The live channel").

A live fatigue node takes the load channel (``plant/arm``) straight from the plant's stream
(#28 item 4); the recorder no longer relays it as blocks on ``recorder/loads``.

A batch must be signed with the run's key (:meth:`Participant.open`); each data message in
it must decode, be on a channel its node declared, and keep the layout of its channel (the
same fields, each a number or a list of one length, as in the channel's first message).
Anything else is rejected and counted, never journaled: one ragged batch cannot make a
complete journal unexportable. A second message for a step a channel already gave (a
duplicate: a records batch replayed into the run, #30 item 12) is counted (``duplicates``,
and as rejected), not journaled: a replay cannot fill the disk. A hole in a channel's steps
(a batch lost on the bus, or rejected, with later ones come) ends the run at once naming the
steps and the producer (:func:`lost_steps`), not at the stall timeout.
"""

from __future__ import annotations

import errno
import logging
import threading
import time
from pathlib import Path
from typing import Any

from cosim import channels as ch
from cosim import keys
from cosim import node_kinds as nk
from cosim.coupling_stream import LiveResidual
from cosim.errors import RunError, WireError
from cosim.journal import JournalReader, JournalWriter
from cosim.listener import Listener, Received
from cosim.participant import Participant
from cosim.run_checkpoint import NodeCheckpoints
from cosim.run_settings import RunSettings
from cosim.table_writer import TableWriter, table_of_journal
from cosim.wire import Message, codec, decode

from .fork_layout import ForkLayouts
from .steps import StepSet

log = logging.getLogger("suscosim.node")
FLUSH_PERIOD_S = 0.05
EARLY_MAX = 100_000
"""Data messages held before the clock's start says which channels the run has."""
STATE_CHANNEL = f"{ch.PLANT}/{ch.STATE}"
"""The channel whose time says which step is the run's last (:meth:`RunSettings.is_last`)."""
LIVE_PERIOD_S = 0.1
"""``recorder/coupling`` is published at most this often (wall time) while the run goes."""


def finalize(journal_path: Path, folder: Path) -> dict[str, Any]:
    """Table, exports and stats from a journal on disk, streamed (a crashed recorder's)."""
    reader: list[JournalReader] = []

    def records() -> JournalReader:
        reader.append(JournalReader(journal_path))
        return reader[-1]

    writer, bad = table_of_journal(records, folder)
    files = writer.close() if writer is not None else {}
    rows = writer.rows if writer is not None else 0
    torn = reader[-1].contents().torn if reader else False
    return {"stats": writer.stats() if writer is not None else {}, "files": files,
            "rows": rows, "torn": torn, "undecodable": bad}


def run(part: Participant, scenario: dict[str, Any]) -> None:
    """Record the run until every channel is complete (or the run is aborted).

    Producers (the coupled kinds of the registry, :func:`cosim.node_kinds.producers`) send
    their data messages, exactly as they published them, in batches on ``<node>/records``
    (see cosim.participant); each one is validated, journaled and put in the table.
    """
    run_cfg = scenario["run"]
    folder = Path(run_cfg["dir"])
    journal_path = folder / "journal.msgpack"
    plan = NodeCheckpoints.of(scenario, part.node)
    if plan.resuming and (plan.journal is None or plan.journal.resolve() ==
                          journal_path.resolve()):
        raise RunError(f"recorder: a resumed run needs the old journal set aside "
                       f"(run.resume.journal = {plan.journal}), not {journal_path}")
    journal = JournalWriter(journal_path, part.run)
    ckpt_due = sorted(plan.due)
    warm = threading.Thread(target=_import_pyarrow, name="pyarrow-import", daemon=True)
    warm.start()  # the table's first row group needs it; importing takes seconds when loaded
    producers = [n for n in run_cfg["nodes"] if n in nk.producers() and n != part.node]
    part.output(ch.COUPLING)  # before the handshake: its hello proves the path live
    listener = Listener(part, run_cfg["start_timeout_s"])
    for node in producers:
        listener.feed(node, keys.RECORDS, kinds=("records",))
    expected: set[str] = set()
    got: dict[str, StepSet] = {}
    table: TableWriter | None = None
    live: LiveResidual | None = None
    early: list[tuple[str, str, bytes, Message]] = []
    n_steps = None
    duplicates = 0
    settings = RunSettings.of(scenario)
    last: tuple[int, float] | None = None  # (k, t) of the run's last step, once known
    gap: str | None = None  # why the run cannot complete: a records batch that never came
    fork = ForkLayouts((run_cfg.get("resume") or {}).get("fresh", ()), plan.start_k)

    def record(node: str, channel: str, raw: bytes, msg: Message | None = None) -> None:
        """Validate, journal and tabulate one data message of ``node/channel``."""
        nonlocal duplicates, last, gap
        if msg is None:  # checked against its channel's schema (cosim/schema.py)
            try:
                msg = codec(f"{node}/{channel}").decode(raw)
            except WireError as exc:
                part.reject((node, channel), str(exc))
                return
        if msg.kind != "data" or msg.k < 0:
            return
        if table is None:  # before the start: which channels the run has is not known yet
            if len(early) < EARLY_MAX:
                early.append((node, channel, raw, msg))
            else:
                part.reject((node, channel), "data before the run's start")
            return
        name = f"{node}/{channel}"
        if n_steps is not None and msg.k > n_steps:
            part.reject((node, channel), f"step {msg.k} after the last step {n_steps}")
            return
        steps = got.get(name)
        if steps is None:
            part.reject((node, channel), f"{name} is not an output {node} declared")
            return
        if msg.k in steps:
            duplicates += 1
            part.reject((node, channel), f"step {msg.k} again (a duplicate: not journaled)")
            return
        if fork.holds(node, msg.k):  # a fork's new law: its layout is known at step k
            fork.hold(name, msg.k, msg.t, msg.d)
        else:
            if name in fork.held:
                try:
                    for k, t, d in fork.release(name, msg.d):
                        tabulate(name, k, t, d)
                except ValueError as exc:
                    raise RunError(f"recorder: the fork's table: {exc}") from None
            wrong = tabulate(name, msg.k, msg.t, fork.pad(name, msg.d))
            if wrong:
                part.reject((node, channel), wrong)
                return
        steps.add(msg.k)
        if gap is None and len(steps.lo) > 1:  # a producer sends in order: a hole is a loss
            gap = lost_steps(node, name, steps)
        journal.append(name, raw)
        if name == STATE_CHANNEL and settings.is_last(msg.k, msg.t):
            last = (msg.k, msg.t)

    def tabulate(name: str, k: int, t: float, d: Any) -> str | None:
        """Put one message in the table (and the live residual); why not, else None."""
        assert table is not None
        rows = table.rows
        wrong = table.add(name, k, t, d)
        if wrong:
            return wrong
        if live is not None:
            live.add(name, k, t, d)
            if table.rows > rows:  # this message completed the row of its step
                live.row(k)
        return None

    def publish_live() -> None:
        """The residual of the rows complete so far on ``recorder/coupling``. A residual
        that cannot be sent (a number beyond the channel's bound) ends the channel with a
        warning, never the recording."""
        nonlocal live
        if live is None or not live.pending:
            return
        try:
            for k, t, d in live.take():
                part.publish(ch.COUPLING, k, t, d, record=False)
        except (RunError, KeyError, ValueError) as exc:
            log.warning("recorder: the live coupling residual stops: %s", exc)
            live = None

    def feed(batch: Received) -> None:
        """One ``records`` batch (verified by the listener): its data messages."""
        for channel, one in batch.msg.d["records"]:
            if not keys.NAME.match(channel):
                part.reject((batch.node, keys.RECORDS), f"bad channel name {channel!r:.40}")
                continue
            record(batch.node, channel, one)

    def done_k() -> int:
        return min(got[c].count for c in expected) - 1

    def replay_journal(path: Path, before_k: int) -> None:
        """A resumed run (:mod:`cosim.run_checkpoint`): the old journal's records of the
        steps < ``before_k``, in their order, through :func:`record` like live ones (the
        journal, the table and the residual are functions of that sequence)."""
        try:
            for i, (name, raw) in enumerate(JournalReader(path)):
                if i % 512 == 0:
                    part.progress(-1, 0.0)  # (rate-limited) alive while it replays
                node, _, channel = name.partition("/")
                try:
                    msg = decode(raw)
                except WireError:
                    continue  # it was journaled valid: a damaged record (counted by its reader)
                if msg.kind == "data" and 0 <= msg.k < before_k:
                    record(node, channel, raw, msg)
        except OSError as exc:
            raise RunError(f"recorder: cannot read the journal {path} the run resumes "
                           f"from: {exc.strerror or exc}") from None
        missing = sorted(c for c in expected if got[c].count < before_k)
        if missing:
            raise RunError(f"recorder: the journal {path} lacks steps < {before_k} of "
                           f"{', '.join(missing)}: the run cannot resume from it")

    def checkpoint(k: int) -> None:
        """The checkpoints due once every step <= ``k`` is in the journal, on the disk."""
        while ckpt_due and ckpt_due[0] - 1 <= k:
            boundary = ckpt_due.pop(0)
            journal.sync()
            plan.save(part, boundary, {"journal": journal_path.name,
                                       "records": journal.records})

    last_flush = last_data = last_live = time.monotonic()
    try:
        while True:
            now = time.monotonic()
            if n_steps is not None and now - last_data > part.stall_timeout_s:
                missing = sorted(c for c in expected if got[c].count <= n_steps)
                raise RunError(f"recorder: no data for {part.stall_timeout_s:.1f} s; "
                               f"incomplete: {', '.join(missing)}")
            if now - last_flush >= FLUSH_PERIOD_S:
                journal.flush()
                last_flush = now
            if now - last_live >= LIVE_PERIOD_S:
                publish_live()
                last_live = now
            batch = listener.poll(timeout=0.05)  # the clock: raises RunError on abort
            if n_steps is None and listener.start is not None:
                n_steps = int(listener.start["n_steps"])
                for node, info in listener.start["info"].items():
                    if node not in producers:
                        continue  # e.g. the fatigue node: not a per-step channel
                    expected.update(f"{node}/{c}" for c in info.get("outputs", []))
                got.update((c, StepSet()) for c in expected)
                if expected:
                    table = TableWriter(expected, folder)
                    live = _live_residual(run_cfg, expected)
                    if plan.resuming and plan.journal is not None:
                        replay_journal(plan.journal, plan.start_k)
                for node, channel, raw, msg in early:
                    record(node, channel, raw, msg)
                early.clear()
                last_data = time.monotonic()
            if batch is None:
                continue
            feed(batch)
            if gap is not None:
                raise RunError(gap)
            last_data = time.monotonic()
            if n_steps is not None and expected:
                k = done_k()
                checkpoint(k)
                part.progress(k, k * run_cfg["h"])
                if last is not None and k >= last[0]:
                    break
    except RunError:
        for batch in listener.drain():  # the other nodes' last batches, sent as they stop
            feed(batch)
        journal.close()
        if table is not None:
            try:
                table.close()  # the rows that are complete, in place
            except OSError as exc:  # a full disk: the journal is the record
                table.abandon()
                log.warning("recorder: table not written: %s", exc)
        raise
    except OSError as exc:  # the journal or the table could not be written (a full disk)
        if table is not None:
            table.abandon()
        try:
            journal.close()
        except OSError:
            pass
        raise _write_error(exc, folder) from None
    journal.close()
    publish_live()  # the last rows' residual, before done (the orchestrator then closes)

    def finish_table() -> dict[str, Any]:
        assert table is not None
        files = table.close()
        return {"stats": table.stats(), "files": files, "rows": table.rows, "torn": False,
                "undecodable": 0, "duplicates": duplicates}

    assert last is not None
    n_steps, t_last = last  # N and t_N (for an adaptive step: known when the run got there)
    try:
        result = _with_heartbeat(part, n_steps, t_last, finish_table,
                                 min(1.0, part.stall_timeout_s / 4))
    except OSError as exc:
        if table is not None:
            table.abandon()
        raise _write_error(exc, folder) from None
    part.finish(n_steps, t_last, **result)


def lost_steps(node: str, name: str, steps: StepSet) -> str:
    """The run's error for the first hole in the steps channel ``name`` delivered.

    A producer sends its records batches in step order on one publisher and Zenoh delivers
    them reliably and in order, so steps missing below one that came were lost on the bus (a
    whole batch: issue #28's dask sweep once lost plant steps 65-96) or rejected here (a
    batch or message that did not verify or decode). Nothing sends them again; waiting for
    the stall timeout would only hide which steps and whose batch."""
    lo, hi = steps.hi[0], steps.lo[1] - 1
    return (f"recorder: {name} steps {lo}-{hi} never arrived (a records batch of {node!r} "
            f"was lost on the bus or rejected; its step {steps.lo[1]} came): the journal "
            f"holds the steps before")


def _live_residual(run_cfg: dict[str, Any], channels: set[str]) -> LiveResidual | None:
    """The live residual of the run's table (None: a scenario without its ``coupling`` and
    ``exchange``, which a resolved scenario always has, says nothing to compute it by)."""
    if "coupling" not in run_cfg or "exchange" not in run_cfg:
        return None
    h = None if run_cfg.get("adaptive") else float(run_cfg["h"])  # None: each step's from t
    return LiveResidual(h, run_cfg["coupling"], run_cfg["exchange"],
                        channels)


def _write_error(exc: OSError, folder: Any) -> RunError:
    """The run's error for a journal or table that could not be written (a full disk)."""
    full = " (the disk is full)" if exc.errno == errno.ENOSPC else ""
    return RunError(f"recorder: cannot write the run's journal or table in {folder}: "
                    f"{exc.strerror or exc}{full}")


def _import_pyarrow() -> None:
    try:
        import pyarrow.parquet  # noqa: F401
    except ImportError:  # the table's writer says so when it needs it
        pass


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
