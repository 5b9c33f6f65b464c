"""The recorder node: every data channel of a run into the journal and, as the rows complete,
into the run's table.

It subscribes to the records feed of every producer node of the run
(``suscosim/<run>/<node>/records``: the node's data messages exactly as it published them, in
batches of a few steps, signed with the run's key: :meth:`Participant.open`) and gives each
message to :class:`.recording.Recording` (what is rejected, the append-only journal of
:mod:`cosim.journal`, the table of :class:`cosim.table_writer.TableWriter` written as rows
complete). Once every channel has delivered every step 0..N it puts the table in place and
reports per-channel statistics to the orchestrator; on an abort it flushes, puts the rows that
are complete in place, and stops. Its memory does not grow with the run: the steps each
channel delivered are ranges (:class:`.recording.StepSet`), the table holds only the steps not yet
complete.

It also publishes the run's coupling energy residual per step and bond on
``recorder/coupling`` (:class:`cosim.coupling_stream.LiveResidual`, at most once per
:data:`LIVE_PERIOD_S` and at the end, signed as its other messages), computed from the
table's rows: what ``summary.json``'s ``coupling_energy_residual`` sums, step by step. It is
not journaled: a journal's table gives it again (docs/coupling_residual.md).
"""

from __future__ import annotations

import contextlib
import logging
import time
from pathlib import Path
from typing import Any

from cosim import channels as ch
from cosim import keys
from cosim import node_kinds as nk
from cosim.errors import RunError, WireError
from cosim.journal import JournalReader, JournalWriter
from cosim.listener import Listener, Received
from cosim.participant import Participant, alive_while_busy
from cosim.run_checkpoint import NodeCheckpoints
from cosim.table_batches import warm_pyarrow
from cosim.table_writer import table_of_journal
from cosim.wire import decode

from .recording import Recording, lost_steps, write_error

__all__ = ["finalize", "lost_steps", "run"]

log = logging.getLogger("suscosim.node")
FLUSH_PERIOD_S = 0.05
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
    """Record the run until every channel is complete (or the run is aborted); the producers
    are the coupled kinds of the registry (:func:`cosim.node_kinds.producers`)."""
    run_cfg = scenario["run"]
    folder = Path(run_cfg["dir"])
    journal_path = folder / "journal.msgpack"
    plan = NodeCheckpoints.of(scenario, part.node)
    if plan.resuming and (plan.journal is None or plan.journal.resolve() ==
                          journal_path.resolve()):
        raise RunError(f"recorder: a resumed run needs the old journal set aside "
                       f"(run.resume.journal = {plan.journal}), not {journal_path}")
    try:
        journal = JournalWriter(journal_path, part.run)
    except OSError as exc:
        raise write_error(exc, folder) from None
    ckpt_due = sorted(plan.due)
    warm_pyarrow()  # the table's first row group needs it
    producers = [n for n in run_cfg["nodes"] if n in nk.producers() and n != part.node]
    part.output(ch.COUPLING)  # before the handshake: its hello proves the path live
    listener = Listener(part, run_cfg["start_timeout_s"])
    for node in producers:
        listener.feed(node, keys.RECORDS, kinds=("records",))
    rec = Recording(scenario, journal, part.reject, plan.start_k)

    def publish_live() -> None:
        """The residual of the rows complete so far on ``recorder/coupling``. A residual
        that cannot be sent (a number beyond the channel's bound) ends the channel with a
        warning, never the recording."""
        live = rec.live
        if live is None or not live.pending:
            return
        try:
            for k, t, d in live.take():
                part.publish(ch.COUPLING, k, t, d, record=False)
        except (RunError, KeyError, ValueError) as exc:
            log.warning("recorder: the live coupling residual stops: %s", exc)
            rec.live = None

    def feed(batch: Received) -> None:
        """One ``records`` batch (verified by the listener): its data messages."""
        for channel, one in batch.msg.d["records"]:
            if not keys.NAME.match(channel):
                part.reject((batch.node, keys.RECORDS), f"bad channel name {channel!r:.40}")
                continue
            rec.record(batch.node, channel, one)

    def replay_journal(path: Path, before_k: int) -> None:
        """A resumed run (:mod:`cosim.run_checkpoint`): the old journal's records of the
        steps < ``before_k``, in their order, through :meth:`Recording.record` like live
        ones (the journal, the table and the residual are functions of that sequence)."""
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
                    rec.record(node, channel, raw, msg)
        except OSError as exc:
            raise RunError(f"recorder: cannot read the journal {path} the run resumes "
                           f"from: {exc.strerror or exc}") from None
        missing = sorted(c for c in rec.expected if rec.got[c].count < before_k)
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
            if rec.n_steps is not None and now - last_data > part.stall_timeout_s:
                missing = sorted(c for c in rec.expected if rec.got[c].count <= rec.n_steps)
                raise RunError(f"recorder: no data for {part.stall_timeout_s:.1f} s; "
                               f"incomplete: {', '.join(missing)}")
            if now - last_flush >= FLUSH_PERIOD_S:
                journal.flush()
                last_flush = now
            if now - last_live >= LIVE_PERIOD_S:
                publish_live()
                last_live = now
            batch = listener.poll(timeout=0.05)  # the clock: raises RunError on abort
            if rec.n_steps is None and listener.start is not None:
                rec.begin(int(listener.start["n_steps"]),
                          (f"{node}/{c}" for node, info in listener.start["info"].items()
                           if node in producers  # e.g. not the fatigue node's
                           for c in info.get("outputs", [])))
                if rec.table is not None and plan.resuming and plan.journal is not None:
                    replay_journal(plan.journal, plan.start_k)
                rec.release_early()
                last_data = time.monotonic()
            if batch is None:
                if rec.n_steps is not None and rec.expected:  # (rate-limited) the plant may
                    k = rec.done_k()  # be holding the chain for it (cosim/sink_window.py)
                    part.progress(k, k * run_cfg["h"])
                continue
            feed(batch)
            if rec.gap is not None:
                raise RunError(rec.gap)
            last_data = time.monotonic()
            if rec.n_steps is not None and rec.expected:
                k = rec.done_k()
                checkpoint(k)
                part.progress(k, k * run_cfg["h"])
                if rec.complete:
                    break
        journal.close()  # its last segment: a full disk here is said as below
    except RunError:
        try:  # the other nodes' last batches, sent as they stop
            for batch in listener.drain():
                feed(batch)
            journal.close()
        except OSError as exc:  # a full disk: the run's error stays the one to say
            log.warning("recorder: the journal's last records not written: %s", exc)
        if rec.table is not None:
            try:
                rec.table.close()  # the rows that are complete, in place
            except OSError as exc:  # a full disk: the journal is the record
                rec.table.abandon()
                log.warning("recorder: table not written: %s", exc)
        raise
    except OSError as exc:  # the journal or the table could not be written (a full disk)
        if rec.table is not None:
            rec.table.abandon()
        with contextlib.suppress(OSError):
            journal.close()
        raise write_error(exc, folder) from None
    publish_live()  # the last rows' residual, before done (the orchestrator then closes)
    assert rec.last is not None
    n_steps, t_last = rec.last  # N and t_N (for an adaptive step: known when it got there)
    try:
        # exporting the table (pyarrow's first import alone takes seconds on a loaded
        # machine) is not a stall
        with alive_while_busy(part, n_steps, t_last, min(1.0, part.stall_timeout_s / 4)):
            result = rec.finish_table()
    except OSError as exc:
        if rec.table is not None:
            rec.table.abandon()
        raise write_error(exc, folder) from None
    part.finish(n_steps, t_last, **result)
