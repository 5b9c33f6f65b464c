"""What one sweep point's work is, wherever it runs (this machine or a Dask worker): the run
phase (``suscosim run``) and the fatigue phase (``suscosim fatigue``), their command lines, the
run folder they start from and how their outcome is judged."""

from __future__ import annotations

import json
import os
import shutil
import socket
import sys
from pathlib import Path
from typing import Any

from cosim.run_folder import read_json

from .procs import _exit_text, _last_error


def point_meta(sweep_name: str, pid: str, params: dict[str, Any], base: str,
               overrides: dict[str, Any], fingerprint: str) -> dict[str, Any]:
    """The content of a run folder's ``point.json`` (the worker is added when it starts)."""
    return {"sweep": sweep_name, "id": pid, "params": params, "base": base,
            "overrides": overrides, "fingerprint": fingerprint}


def this_worker(executor: str = "local", **extra: Any) -> dict[str, Any]:
    """Who runs a point: the executor, the host name and the process id (plus ``extra``,
    e.g. a Dask worker's address and name)."""
    return {"executor": executor, "host": socket.gethostname(), "pid": os.getpid(), **extra}


def prepare_run_dir(run_dir: Path, meta: dict[str, Any], worker: dict[str, Any]) -> None:
    """A clean run folder (a failed or stale attempt is deleted) with its ``point.json``."""
    if run_dir.exists():
        shutil.rmtree(run_dir)
    run_dir.mkdir(parents=True)
    write_point_json(run_dir, {**meta, "worker": worker})


def write_point_json(run_dir: Path, doc: dict[str, Any]) -> None:
    (run_dir / "point.json").write_text(json.dumps(doc, indent=2, default=str))


def run_command(base: str, run_dir: Path, set_args: list[str], pin_off: bool,
                connect: list[str] = (), external: list[str] = ()) -> list[str]:  # type: ignore[assignment]
    """``suscosim run BASE --out RUN_DIR --quiet --set ...`` (unpinned when runs share the
    machine's cores)."""
    cmd = [sys.executable, "-m", "orchestrator", "run", base, "--out", str(run_dir), "--quiet"]
    if pin_off:  # runs side by side: pinning each to the same cores hurts
        cmd += ["--pin", "off"]
    for s in set_args:
        cmd += ["--set", s]
    for ep in connect:
        cmd += ["--connect", ep]
    for n in external:
        cmd += ["--external", n]
    return cmd


def fork_command(spec: str, run_dir: Path, set_args: list[str], pin_off: bool,
                 connect: list[str] = ()) -> list[str]:  # type: ignore[assignment]
    """``suscosim run --fork PARENT_DIR@T --out RUN_DIR --quiet --set ...`` ([sweep]
    fork_at: the point's run continues its group's parent from its checkpoint at T)."""
    cmd = [sys.executable, "-m", "orchestrator", "run", "--fork", spec, "--out", str(run_dir),
           "--quiet"]
    if pin_off:
        cmd += ["--pin", "off"]
    for s in set_args:
        cmd += ["--set", s]
    for ep in connect:
        cmd += ["--connect", ep]
    return cmd


def fatigue_command(run_dir: Path) -> list[str]:
    return [sys.executable, "-m", "orchestrator", "fatigue", str(run_dir)]


def run_outcome(code: int, run_dir: Path, log: Path, fatigue: bool) -> tuple[str, str]:
    """The run phase ended with exit ``code``: ``("ok", "")``, ``("fatigue", "")`` (ok, but
    the fatigue phase is still to do: no live fatigue node wrote it) or ``("failed", why)``."""
    summary = read_json(run_dir / "summary.json")
    if code == 0 and isinstance(summary, dict) and summary.get("status") == "ok":
        if fatigue and not isinstance(read_json(run_dir / "fatigue" / "summary.json"), dict):
            return "fatigue", ""
        return "ok", ""
    err = summary.get("error", "") if isinstance(summary, dict) else ""
    err = err or _last_error(log)
    return "failed", f"run {_exit_text(code)}" + (f": {err}" if err else "")


def fatigue_outcome(code: int, run_dir: Path, log: Path) -> tuple[str, str]:
    """The fatigue phase ended with exit ``code``: ``("ok", "")`` or ``("failed", why)``."""
    if code == 0 and isinstance(read_json(run_dir / "fatigue" / "summary.json"), dict):
        return "ok", ""
    err = _last_error(log)
    return "failed", f"fatigue {_exit_text(code)}" + (f": {err}" if err else "")
