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
journal's last segments only, against ``run.n_steps``. The whole journal is also walked
(segment headers and CRCs, nothing decompressed) by the reader ``suscosim export`` uses, so
both give the same ``records`` and ``skipped_records``; a damaged or torn journal is named in
the NOTE column (and in ``--json``) with what export will skip, and so is an ``ok`` run whose
journal ends before its last step (cut short after the run). DIR is each run's folder.

``run.json`` is written by the runner right after ``scenario.json``:
``{"run_id", "pid", "pid_start", "host", "started", "mode", "endpoints": {"listen": [...],
"connect": [...]}, "lowlatency", "state": "started"}``; ``summary.json`` is the authority on
how a run ended. ``suscosim tap RUN_DIR`` reads the endpoints from it.

Exit codes: 0 listed (also when there is no run), 2 ``DIR`` is not a folder.
"""

from __future__ import annotations

import argparse
import json
import socket
import sys
from pathlib import Path
from typing import Any

from cosim.run_folder import SCENARIO_JSON, run_info

from .cli_util import fail, parse_args

MAX_DEPTH = 3


def find_runs(root: Path, depth: int = MAX_DEPTH) -> list[Path]:
    """Run folders (holding ``scenario.json``) in ``root``, up to ``depth`` levels down."""
    if (root / SCENARIO_JSON).is_file():
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
    rows = [("ID", "NAME", "MODE", "STATUS", "STEPS", "STARTED", "DIR", "NOTE")]
    for r in runs:
        note = r["error"]
        if r["status"] == "running" and r["endpoints"].get("listen"):
            note = f"tap: suscosim tap {r['dir']}"
        rows.append((r["id"], r["name"], r["mode"], r["status"], _steps_text(r),
                     (r["started"] or "")[:19].replace("T", " "), r["dir"], note))
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
    args = parse_args(ap, argv)
    if isinstance(args, int):
        return args
    root = Path(args.dir)
    if not root.is_dir():
        return fail("suscosim runs", f"{root}: not a folder")
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
