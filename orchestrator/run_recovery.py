"""What a failed or interrupted run leaves as its table, within seconds whatever its length."""

from __future__ import annotations

import math
import time
from contextlib import suppress
from pathlib import Path
from typing import Any

INTERRUPT_REBUILD_BYTES = 4 << 20
"""[bytes] Largest journal rebuilt into a table on an interrupt (~0.7 s at ~5.5 MB/s on the
2-core machine); a larger one is left for ``suscosim export``."""
RECORDER_WAIT_S = 1.5  # [s] wait for the table of a recorder running elsewhere


def recover_table(folder: Path, interrupted: bool = False, since: float | None = None,
                  recorder_elsewhere: bool = False, wait_s: float = RECORDER_WAIT_S
                  ) -> dict[str, Any]:
    """After a failed run: the journal as a table, never in place of a larger one; the
    recorder's own table taken when written ``since`` [Unix s] the start and complete."""
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
    """Remove the ``.table.*.PID.TID.tmp`` files of a recorder that is gone."""
    from cosim.run_folder import pid_alive

    for tmp in folder.glob(".table.*.tmp"):
        parts = tmp.name.split(".")
        pid = int(parts[3]) if len(parts) > 4 and parts[3].isdigit() else None
        if pid is not None and not pid_alive(pid):
            with suppress(OSError):
                tmp.unlink()


def _remove_tables(folder: Path, stem: str) -> None:
    for suffix in (".csv", ".parquet"):
        with suppress(OSError):
            (folder / f"{stem}{suffix}").unlink(missing_ok=True)


def _recorders_table(folder: Path, journal: Path, since: float | None) -> dict[str, Any] | None:
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
