"""``suscosim runs``: list run folders and their state, from the files alone.

    suscosim runs [DIR] [--json]

A run folder is a folder holding ``scenario.json`` (written by ``suscosim run`` before anything
starts). ``DIR`` (default ``runs``) may hold run folders, or folders of run folders one or two
levels deeper (a sweep: ``SWEEP_DIR/runs/*``). Nothing is asked of a running orchestrator, so
a restarted orchestrator (or anyone with the folder) can tell what happened:

* ``ok`` / ``failed``: ``summary.json`` says so (written at the end of every run, also a
  failed one; its ``error`` is shown);
* ``running``: no ``summary.json`` yet, and the orchestrator process recorded in ``run.json``
  is alive (same host, same pid, same process start time: a reused pid is not taken for it);
* ``interrupted``: no ``summary.json`` and that process is gone (killed, machine rebooted);
* ``unknown``: no ``summary.json`` and no way to tell (no ``run.json``: a run from before it
  existed; or the orchestrator ran on another host).

Steps are the last step ``k`` every channel of the journal has reached, read from the
journal's last 64 KiB only, against ``run.n_steps``. The whole journal is also walked (frames
and CRCs only, ~2.5 us a record) by the reader ``suscosim export`` uses, so both give the same
``records`` and ``skipped_records``; a damaged journal is named in the NOTE column (and in
``--json``) with what export will skip.

``run.json`` is written by the runner right after ``scenario.json``:
``{"run_id", "pid", "pid_start", "host", "started", "mode", "endpoints": {"listen": [...],
"connect": [...]}, "lowlatency", "state": "started"}``; ``summary.json`` is the authority on
how a run ended. ``suscosim tap RUN_DIR`` reads the endpoints from it.

Exit codes: 0 listed (also when there is no run), 2 ``DIR`` is not a folder.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import json
import os
import socket
import sys
from pathlib import Path
from typing import Any

import msgpack

RUN_JSON = "run.json"
TAIL_BYTES = 64 * 1024
MAX_DEPTH = 3
STATUSES = ("ok", "failed", "running", "interrupted", "unknown")


# ---- run.json (written by the runner) ------------------------------------------------------
def _proc_start(pid: int) -> int | None:
    """Start time of process ``pid`` in clock ticks since boot (Linux ``/proc``), or None."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    # Field 2 (comm) may hold spaces and parentheses: split after its closing one.
    fields = stat[stat.rfind(")") + 2:].split()
    try:
        return int(fields[19])  # field 22 of the whole line
    except (IndexError, ValueError):
        return None


def write_run_json(folder: Path, run_id: str, listen: list[str] | None,
                   connect: list[str] | None, lowlatency: bool = False) -> dict[str, Any]:
    """Record who runs ``folder`` and where its bus is (for ``suscosim runs`` and ``tap``)."""
    scenario_mode = ""
    try:
        scenario_mode = json.loads((folder / "scenario.json").read_text())["run"]["mode"]
    except (OSError, ValueError, KeyError, TypeError):
        pass
    info = {
        "run_id": run_id, "pid": os.getpid(), "pid_start": _proc_start(os.getpid()),
        "host": socket.gethostname(),
        "started": _dt.datetime.now().astimezone().isoformat(timespec="seconds"),
        "mode": scenario_mode,
        "endpoints": {"listen": list(listen or []), "connect": list(connect or [])},
        "lowlatency": bool(lowlatency), "state": "started",
    }
    (Path(folder) / RUN_JSON).write_text(json.dumps(info, indent=2))
    return info


# ---- reading a run folder -----------------------------------------------------------------
def _read_json(path: Path) -> dict[str, Any] | None:
    try:
        obj = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return obj if isinstance(obj, dict) else None


def pid_alive(pid: int, pid_start: int | None = None) -> bool:
    """Whether process ``pid`` exists (and is not a zombie), and is the one that started at
    ``pid_start`` (clock ticks since boot) when that is given and ``/proc`` can tell."""
    if not isinstance(pid, int) or pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's process: it exists
        pass
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
        if stat[stat.rfind(")") + 2:].split()[0] == "Z":
            return False
    except (OSError, IndexError):
        pass
    if pid_start is not None:
        now = _proc_start(pid)
        if now is not None and now != pid_start:
            return False
    return True


def journal_tail_steps(path: Path, tail_bytes: int = TAIL_BYTES) -> int | None:
    """The last step ``k`` every channel in the journal's tail has reached, or None.

    Only the header and the last ``tail_bytes`` are read, by the journal reader every other
    command uses (:func:`nodes.recorder.journal.read_journal`; it finds the first intact record
    of the tail by its CRC)."""
    from nodes.recorder.journal import read_journal

    try:
        contents = read_journal(path, tail_bytes=tail_bytes)
    except (OSError, ValueError):
        return None
    return _min_last_k(contents.records)


def journal_integrity(path: Path) -> dict[str, Any]:
    """What ``suscosim export`` would find in the journal: intact ``records``,
    ``skipped_records`` (damaged, stepped over), ``torn`` and ``problem`` (one line)."""
    from nodes.recorder.journal import read_journal

    try:
        c = read_journal(path)
    except (OSError, ValueError) as exc:
        return {"records": None, "skipped_records": None, "torn": False, "problem": str(exc)}
    return {"records": len(c.records), "skipped_records": c.skipped_records, "torn": c.torn,
            "problem": c.problem}


def _min_last_k(records: list[tuple[str, bytes]]) -> int | None:
    last: dict[str, int] = {}
    for channel, raw in records:
        try:
            obj = msgpack.unpackb(raw, raw=False)
            k = obj["k"] if isinstance(obj, dict) and obj.get("kind") == "data" else None
        except Exception:
            continue
        if isinstance(k, int):
            last[channel] = max(last.get(channel, -1), k)
    return min(last.values()) if last else None


def run_info(folder: Path, host: str | None = None) -> dict[str, Any]:
    """What the files of one run folder say about it (see the module docstring)."""
    host = host or socket.gethostname()
    scenario = _read_json(folder / "scenario.json") or {}
    run = scenario.get("run") if isinstance(scenario.get("run"), dict) else {}
    meta = _read_json(folder / RUN_JSON)
    summary = _read_json(folder / "summary.json")
    info: dict[str, Any] = {
        "dir": str(folder), "id": (meta or {}).get("run_id") or run.get("id") or folder.name,
        "name": run.get("name", ""), "mode": run.get("mode") or (meta or {}).get("mode", ""),
        "n_steps": run.get("n_steps"), "steps": None, "status": "unknown", "error": "",
        "started": (meta or {}).get("started") or _mtime(folder / "scenario.json"),
        "pid": (meta or {}).get("pid"), "endpoints": (meta or {}).get("endpoints", {}),
        "lowlatency": bool((meta or {}).get("lowlatency", False)),
    }
    if summary is not None:
        info["status"] = summary.get("status") if summary.get("status") in STATUSES else "unknown"
        info["error"] = str(summary.get("error") or "")
    elif meta is None:
        info["error"] = "no run.json and no summary.json: cannot tell"
    elif meta.get("host") not in (None, host):
        info["error"] = f"orchestrator on host {meta.get('host')}: cannot check its process"
    else:
        alive = pid_alive(meta.get("pid"), meta.get("pid_start"))
        info["status"] = "running" if alive else "interrupted"
        if not alive:
            info["error"] = f"orchestrator (pid {meta.get('pid')}) is gone, no summary.json"
    journal = folder / "journal.msgpack"
    info["records"] = info["skipped_records"] = None
    if journal.exists():
        info["steps"] = journal_tail_steps(journal)
        integrity = journal_integrity(journal)
        info["records"] = integrity["records"]
        info["skipped_records"] = integrity["skipped_records"]
        if integrity["skipped_records"] or integrity["records"] is None:
            note = f"journal: {integrity['problem']}"
            info["error"] = f"{info['error']}; {note}" if info["error"] else note
    elif summary is not None and summary.get("rows"):
        info["steps"] = int(summary["rows"]) - 1
    return info


def _mtime(path: Path) -> str:
    try:
        ts = path.stat().st_mtime
    except OSError:
        return ""
    return _dt.datetime.fromtimestamp(ts).astimezone().isoformat(timespec="seconds")


def find_runs(root: Path, depth: int = MAX_DEPTH) -> list[Path]:
    """Run folders (holding ``scenario.json``) in ``root``, up to ``depth`` levels down."""
    if (root / "scenario.json").is_file():
        return [root]
    if depth <= 0:
        return []
    found: list[Path] = []
    try:
        children = sorted(p for p in root.iterdir() if p.is_dir())
    except OSError:
        return []
    for child in children:
        found += find_runs(child, depth - 1)
    return found


def list_runs(root: Path) -> list[dict[str, Any]]:
    """Every run under ``root``, oldest first."""
    host = socket.gethostname()
    runs = [run_info(p, host) for p in find_runs(Path(root))]
    return sorted(runs, key=lambda r: (r["started"] or "", r["dir"]))


def _steps_text(r: dict[str, Any]) -> str:
    steps = "?" if r["steps"] is None else str(r["steps"])
    total = "?" if r["n_steps"] is None else str(r["n_steps"])
    return f"{steps}/{total}"


def format_table(runs: list[dict[str, Any]]) -> str:
    """A plain-text table of :func:`list_runs`' result."""
    rows = [("ID", "NAME", "MODE", "STATUS", "STEPS", "STARTED", "NOTE")]
    for r in runs:
        note = r["error"]
        if r["status"] == "running" and r["endpoints"].get("listen"):
            note = f"tap: suscosim tap {r['dir']}"
        rows.append((r["id"], r["name"], r["mode"], r["status"], _steps_text(r),
                     (r["started"] or "")[:19].replace("T", " "), note))
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]) - 1)]
    return "\n".join("  ".join(c.ljust(w) for c, w in zip(row[:-1], widths, strict=True))
                     + ("  " + row[-1] if row[-1] else "") for row in rows).rstrip()


def main(argv: list[str] | None = None) -> int:
    """List the runs under DIR; return the exit code (0, or 2 for a bad DIR)."""
    ap = argparse.ArgumentParser(prog="suscosim runs",
                                 description="list runs and their state from the run folders")
    ap.add_argument("dir", nargs="?", default="runs",
                    help="folder of run folders, a sweep folder, or one run folder "
                         "(default: runs)")
    ap.add_argument("--json", action="store_true", help="print JSON (a list of runs)")
    try:
        args = ap.parse_args(list(sys.argv[1:] if argv is None else argv))
    except SystemExit as exc:
        return 0 if exc.code == 0 else 2
    root = Path(args.dir)
    if not root.is_dir():
        print(f"suscosim runs: {root}: not a folder", file=sys.stderr)
        return 2
    runs = list_runs(root)
    if args.json:
        print(json.dumps(runs, indent=2))
    elif not runs:
        print(f"no runs in {root}")
    else:
        print(format_table(runs))
    return 0


if __name__ == "__main__":
    sys.exit(main())
