"""The run folder: what a run writes where, and reading it back. In the order written:

==================  ==========================================================================
``scenario.json``   the scenario as resolved (written before anything starts)
``run.json``        who runs it and where its bus is: ``{"run_id", "pid", "pid_start", "host",
                    "started", "mode", "endpoints": {"listen", "connect"}, "lowlatency",
                    "state"}`` (:func:`write_run_json`; ``state`` "started", then the run's
                    status and ``ended`` by :func:`mark_run_ended`)
``journal.msgpack`` every data message as received (:mod:`cosim.journal`)
``table.*``         every channel against time (:mod:`cosim.table`)
``summary.json``    how the run ended: the authority on ``ok`` / ``failed``
``fatigue/``        the lower arm's damage (``summary.json``, ``damage_per_node.csv``, map)
==================  ==========================================================================

A run's state (:func:`run_info`), from the files alone: ``ok`` / ``failed`` as
``summary.json`` says; without one, ``running`` while the orchestrator process of ``run.json``
is alive (same host, pid and start time), ``interrupted`` once it is gone, ``unknown`` when
there is no telling (no ``run.json``, or another host).
"""

from __future__ import annotations

import datetime as _dt
import json
import os
import socket
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, TextIO

from .journal import last_step, scan_journal

SCENARIO_JSON = "scenario.json"
RUN_JSON = "run.json"
SUMMARY_JSON = "summary.json"
JOURNAL = "journal.msgpack"
STATUSES = ("ok", "failed", "running", "interrupted", "unknown")


def read_json(path: Path) -> Any:
    """The JSON document in ``path``, or None (missing, unreadable, not JSON)."""
    try:
        return json.loads(Path(path).read_text())
    except (OSError, UnicodeDecodeError, ValueError):
        return None


def _dict(obj: Any) -> dict[str, Any] | None:
    return obj if isinstance(obj, dict) else None


@contextmanager
def replaced(path: str | Path, newline: str | None = None) -> Iterator[TextIO]:
    """A text file opened beside ``path`` (UTF-8), renamed over it when the block ends: a
    reader sees the old file or the new one, never half of one; removed on an error."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with open(tmp, "w", encoding="utf-8", newline=newline) as fh:
            yield fh
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def write_json(obj: object, path: str | Path) -> None:
    """Write ``obj`` as strict JSON (NaN: a ValueError) through :func:`replaced`."""
    text = json.dumps(obj, indent=2, sort_keys=True, allow_nan=False) + "\n"
    with replaced(path) as fh:
        fh.write(text)


# ---- run.json (written by the runner) ------------------------------------------------------
def _proc_stat(pid: int) -> list[str]:
    """Fields 3.. of ``/proc/<pid>/stat`` ([] if unreadable), after comm (may hold spaces)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return []
    return stat[stat.rfind(")") + 2:].split()


def _proc_start(pid: int) -> int | None:
    """Start time of process ``pid`` in clock ticks since boot, or None."""
    fields = _proc_stat(pid)
    return int(fields[19]) if len(fields) > 19 and fields[19].isdigit() else None


def write_run_json(folder: Path, run_id: str, listen: list[str] | None,
                   connect: list[str] | None, lowlatency: bool = False) -> dict[str, Any]:
    """Record who runs ``folder`` and where its bus is (``suscosim runs``, ``tap``)."""
    scenario = read_json(Path(folder) / SCENARIO_JSON)
    run = scenario.get("run") if isinstance(scenario, dict) else None
    scenario_mode = str(run.get("mode", "")) if isinstance(run, dict) else ""
    info = {
        "run_id": run_id, "pid": os.getpid(), "pid_start": _proc_start(os.getpid()),
        "host": socket.gethostname(),
        "started": _dt.datetime.now().astimezone().isoformat(timespec="seconds"),
        "mode": scenario_mode,
        "endpoints": {"listen": list(listen or []), "connect": list(connect or [])},
        "lowlatency": bool(lowlatency), "state": "started",
    }
    write_json(info, Path(folder) / RUN_JSON)
    return info


def mark_run_ended(folder: Path, status: str) -> None:
    """Say in ``run.json`` that the run has ended (after ``summary.json``)."""
    path = Path(folder) / RUN_JSON
    info = _dict(read_json(path))
    if info is None:
        return
    info["state"] = status
    info["ended"] = _dt.datetime.now().astimezone().isoformat(timespec="seconds")
    write_json(info, path)


# ---- reading a run folder ----------------------------------------------------------------
def pid_alive(pid: int, pid_start: int | None = None) -> bool:
    """Whether process ``pid`` exists (not a zombie) and, when ``pid_start`` (clock ticks
    since boot) is given and ``/proc`` can tell, started then."""
    if not isinstance(pid, int) or pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's process: it exists
        pass
    if _proc_stat(pid)[:1] == ["Z"]:
        return False
    if pid_start is not None:
        now = _proc_start(pid)
        if now is not None and now != pid_start:
            return False
    return True


def journal_integrity(path: Path) -> dict[str, Any]:
    """Intact ``records``, ``skipped_records``, ``torn``, ``problem`` of a journal."""
    try:
        c = scan_journal(path)
    except (OSError, ValueError) as exc:
        return {"records": None, "skipped_records": None, "torn": False, "problem": str(exc)}
    return {"records": c.count, "skipped_records": c.skipped_records, "torn": c.torn,
            "problem": c.problem}


def run_info(folder: Path, host: str | None = None) -> dict[str, Any]:
    """What the files of one run folder say about it."""
    host = host or socket.gethostname()
    scenario = _dict(read_json(folder / SCENARIO_JSON)) or {}
    run: dict[str, Any] = _dict(scenario.get("run")) or {}
    meta = _dict(read_json(folder / RUN_JSON))
    summary = _dict(read_json(folder / SUMMARY_JSON))
    info: dict[str, Any] = {
        "dir": str(folder), "id": (meta or {}).get("run_id") or run.get("id") or folder.name,
        "name": run.get("name", ""), "mode": run.get("mode") or (meta or {}).get("mode", ""),
        "n_steps": run.get("n_steps"), "steps": None, "status": "unknown", "error": "",
        "started": (meta or {}).get("started") or _mtime(folder / SCENARIO_JSON),
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
        pid, pid_start = meta.get("pid"), meta.get("pid_start")
        alive = isinstance(pid, int) and pid_alive(pid, pid_start if isinstance(pid_start, int)
                                                   else None)
        info["status"] = "running" if alive else "interrupted"
        if not alive:
            info["error"] = f"orchestrator (pid {meta.get('pid')}) is gone, no summary.json"
    journal = folder / JOURNAL
    info["records"] = info["skipped_records"] = None
    if journal.exists():
        info["steps"] = last_step(journal)
        integrity = journal_integrity(journal)
        info["records"] = integrity["records"]
        info["skipped_records"] = integrity["skipped_records"]
        note = ""
        if integrity["skipped_records"] or integrity["records"] is None or integrity["torn"]:
            note = f"journal: {integrity['problem']}"
        n_steps, steps = info["n_steps"], info["steps"]
        if info["status"] == "ok" and isinstance(n_steps, int) and (steps is None
                                                                    or steps < n_steps):
            # an ok run whose journal ends early was cut after the run
            reach = f"ends at step {steps}" if steps is not None else "holds no complete step"
            note = (f"{note}; " if note else "journal: ") + \
                f"{reach} of {n_steps}: cut short after the run (the table is the record)"
        if note:
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
