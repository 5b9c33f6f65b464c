"""``suscosim runs [DIR] [--json]``: list run folders and their state, from the files alone.
A run folder holds ``scenario.json``; ``DIR`` (default ``runs``) holds them up to three levels
down (a sweep). States: ``ok``/``failed`` (``summary.json``); ``running`` (``run.json``'s
orchestrator process is alive: same host, pid, start time); ``interrupted`` (it is gone);
``unknown`` (no ``run.json``, or another host). Steps: the last ``k`` every journal channel
reached; a damaged journal is named in NOTE (:func:`cosim.run_folder.run_info`).
Exit codes: 0 listed, 2 ``DIR`` is not a folder.
"""

from __future__ import annotations

import argparse
import json
import socket
from pathlib import Path
from typing import Any

from cosim.run_folder import SCENARIO_JSON, run_info

from .cli_util import fail, parse_args

MAX_DEPTH = 3


def find_runs(root: Path, depth: int = MAX_DEPTH) -> list[Path]:
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
    host = socket.gethostname()
    runs = [run_info(p, host) for p in find_runs(Path(root))]
    return sorted(runs, key=lambda r: (r["started"] or "", r["dir"]))


def _steps_text(r: dict[str, Any]) -> str:
    steps = "?" if r["steps"] is None else str(r["steps"])
    total = "?" if r["n_steps"] is None else str(r["n_steps"])
    return f"{steps}/{total}"


def format_table(runs: list[dict[str, Any]]) -> str:
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
    ap = argparse.ArgumentParser(prog="suscosim runs",
                                 description="list runs and their state from the run folders")
    ap.add_argument("dir", nargs="?", default="runs",
                    help="folder of run folders, a sweep folder, or one run folder (default: runs)")
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
