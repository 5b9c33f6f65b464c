"""What a failed or interrupted run leaves as its table: one writer per table, and a stopped
run that ends within seconds whatever its length (issues #15, #18)."""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

INTERRUPT_REBUILD_BYTES = 4 << 20
"""On an interrupt (Ctrl-C, SIGTERM: ``docker compose down``) the orchestrator rebuilds the
table from a journal of up to this size [bytes] (~0.7 s on this 2-core machine: the journal
of a Chapter 6 run rebuilds at ~5.5 MB/s, read, decode, CSV and Parquet); a larger journal
is left for ``suscosim export``, so that a stopped run ends within seconds whatever its
length (issue #18: under 3 s a container)."""


RECORDER_WAIT_S = 1.5
"""How long the orchestrator waits for the table of a recorder running elsewhere [s]."""


def recover_table(folder: Path, interrupted: bool = False, since: float | None = None,
                  recorder_elsewhere: bool = False, wait_s: float = RECORDER_WAIT_S
                  ) -> dict[str, Any]:
    """After a failed run: whatever the journal holds, as a table, never put in place of a
    larger one (:func:`cosim.table.export_target`); one that cannot be written is removed.
    The recorder's own table, written ``since`` the run began [s, Unix time] and holding every
    step the journal reached, is taken as it is (waited for up to ``wait_s`` when
    ``recorder_elsewhere``). On an ``interrupted`` run, or a recorder elsewhere, a journal
    above :data:`INTERRUPT_REBUILD_BYTES` is not rebuilt here: the summary says how."""
    journal = folder / "journal.msgpack"
    if not recorder_elsewhere:
        _remove_stale_tables(folder)
    if not journal.exists():
        return {}
    from cosim.journal import JournalReader
    from cosim.table import export_target
    from cosim.table_writer import table_of_journal

    deadline = time.monotonic() + (wait_s if recorder_elsewhere else 0.0)
    while (taken := _recorders_table(folder, journal, since)) is None \
            and time.monotonic() < deadline:
        time.sleep(0.1)
    if taken is not None:
        return taken
    size = journal.stat().st_size
    if (interrupted or recorder_elsewhere) and size > INTERRUPT_REBUILD_BYTES:
        from cosim.journal import last_step

        reached = last_step(journal)
        why = ("interrupted" if interrupted else
               "the recorder, running elsewhere, exports the table when it has the abort")
        return {"rows": 0 if reached is None else reached + 1, "files": {},
                "note": f"{why}: the table was not rebuilt here from the journal "
                        f"({size / 2**20:.0f} MB); `suscosim export {journal}` does it"}
    readers: list[JournalReader] = []

    def records() -> JournalReader:
        readers.append(JournalReader(journal))
        return readers[-1]

    stem = "table"
    try:
        writer, bad = table_of_journal(records, folder)  # streamed: bounded memory (#32)
    except OSError as exc:
        _remove_tables(folder, stem)
        return {"error": f"table not written: {exc.strerror or exc}"}
    except Exception as exc:  # the run already failed: report, do not mask that error
        return {"error": f"journal unreadable: {type(exc).__name__}: {exc}"}
    contents = readers[-1].contents()
    rows = writer.rows if writer is not None else 0
    rec: dict[str, Any] = {"stats": {}, "files": {}, "rows": rows, "torn": contents.torn,
                           "undecodable": bad, "skipped_records": contents.skipped_records}
    if contents.problem:
        rec["journal"] = contents.problem
    if writer is None or not rows:
        if writer is not None:
            writer.abandon()
        return rec
    try:
        stem, why = export_target(folder, rows, contents.damaged)
        rec["files"] = writer.close(stem)
        rec["stats"] = writer.stats()
        if why:
            rec["note"] = f"table written as {stem}.*: {why}"
    except OSError as exc:
        writer.abandon()
        _remove_tables(folder, stem)
        rec["error"] = f"table not written: {exc.strerror or exc}"
    return rec


def _remove_stale_tables(folder: Path) -> None:
    """The tables a killed recorder was writing beside their place (``.table.csv.PID.TID.tmp``,
    as long as its run: up to hundreds of MB) are removed once that process is gone; the
    journal is the record."""
    from cosim.run_folder import pid_alive

    for tmp in folder.glob(".table.*.tmp"):
        parts = tmp.name.split(".")
        pid = int(parts[3]) if len(parts) > 4 and parts[3].isdigit() else None
        if pid is not None and not pid_alive(pid):
            try:
                tmp.unlink()
            except OSError:
                pass


def _remove_tables(folder: Path, stem: str) -> None:
    """A table that could not be written whole is not left half-written."""
    for suffix in (".csv", ".parquet"):
        try:
            (folder / f"{stem}{suffix}").unlink(missing_ok=True)
        except OSError:
            pass


def _recorders_table(folder: Path, journal: Path, since: float | None) -> dict[str, Any] | None:
    """The recorder's table in ``folder``, when it was written ``since`` the run began and
    holds every step the journal reached: its statistics, rows and files."""
    from cosim.journal import last_step
    from cosim.table import channel_stats, read_table, table_rows

    reached, have = last_step(journal), table_rows(folder)
    fresh = since is None or _mtime(folder / "table.parquet") >= since
    if reached is None or have is None or have < reached + 1 or not fresh:
        return None
    try:
        table = read_table(folder / "table.parquet")
    except Exception:  # not readable after all (being replaced): not taken
        return None
    return {"stats": channel_stats(table), "rows": int(len(table["t"])),
            "files": {"csv": str(folder / "table.csv"),
                      "parquet": str(folder / "table.parquet")},
            "note": "the table the recorder exported"}


def _mtime(path: Path) -> float:
    try:
        return path.stat().st_mtime
    except OSError:
        return -math.inf
