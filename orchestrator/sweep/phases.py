"""One sweep point's work, wherever it runs (this machine or a Dask worker): the run phase
(``suscosim run``) and the fatigue phase (``suscosim fatigue``), their command lines, the run
folder they start from, how their outcome and a folder's state are judged. Each runs as a child
in its own session, so a crashed run cannot take the sweep down and its node processes are
killed with it."""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
from collections.abc import Callable
from contextlib import suppress
from pathlib import Path
from typing import Any

from cosim.run_folder import read_json, replaced

from .spec import Point

ROOT = Path(__file__).resolve().parents[2]


def child_env() -> dict[str, str]:
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), *filter(None, [env.get("PYTHONPATH")])])
    return env


def start(cmd: list[str], log: Path,
           preexec_fn: Callable[[], None] | None = None) -> subprocess.Popen:
    with open(log, "ab") as fh:
        return subprocess.Popen(cmd, stdout=fh, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL, env=child_env(),
                                start_new_session=True, preexec_fn=preexec_fn)


def kill_group(proc: subprocess.Popen, sig: int = signal.SIGTERM) -> None:
    """Signal the process group of one of our children (its node processes too)."""
    with suppress(ProcessLookupError, PermissionError):
        os.killpg(proc.pid, sig)


def _last_error(log: Path) -> str:
    try:
        lines = [ln.strip() for ln in log.read_text(errors="replace").splitlines() if ln.strip()]
    except OSError:
        return ""
    for ln in reversed(lines):
        if "error" in ln.lower():
            return ln[:300]
    return ""


def _exit_text(code: int) -> str:
    if code < 0:
        try:
            return f"killed by signal {signal.Signals(-code).name}"
        except ValueError:
            return f"killed by signal {-code}"
    return f"exited with code {code}"


def point_meta(sweep_name: str, pid: str, params: dict[str, Any], base: str,
               overrides: dict[str, Any], fingerprint: str) -> dict[str, Any]:
    """The content of a run folder's ``point.json`` (the worker is added when it starts)."""
    return {"sweep": sweep_name, "id": pid, "params": params, "base": base,
            "overrides": overrides, "fingerprint": fingerprint}


def this_worker(executor: str = "local", **extra: Any) -> dict[str, Any]:
    """Who runs a point: the executor, host name, process id (and ``extra``)."""
    return {"executor": executor, "host": socket.gethostname(), "pid": os.getpid(), **extra}


def prepare_run_dir(run_dir: Path, meta: dict[str, Any], worker: dict[str, Any]) -> None:
    """A clean run folder (a failed or stale attempt is deleted) with its ``point.json``."""
    if run_dir.exists():
        shutil.rmtree(run_dir)
    run_dir.mkdir(parents=True)
    write_point_json(run_dir, {**meta, "worker": worker})


def write_point_json(run_dir: Path, doc: dict[str, Any]) -> None:
    with replaced(run_dir / "point.json") as fh:
        fh.write(json.dumps(doc, indent=2, default=str))


def run_command(source: list[str], run_dir: Path, set_args: list[str], pin_off: bool,
                connect: list[str] = (), external: list[str] = ()) -> list[str]:  # type: ignore[assignment]
    """``suscosim run SOURCE --out RUN_DIR --quiet --set ...`` (``[BASE]`` or a ``--fork``)."""
    cmd = [sys.executable, "-m", "orchestrator", "run", *source, "--out", str(run_dir),
           "--quiet"]
    if pin_off:  # runs side by side: pinning each to the same cores hurts
        cmd += ["--pin", "off"]
    for s in set_args:
        cmd += ["--set", s]
    for ep in connect:
        cmd += ["--connect", ep]
    for n in external:
        cmd += ["--external", n]
    return cmd


def fatigue_command(run_dir: Path) -> list[str]:
    return [sys.executable, "-m", "orchestrator", "fatigue", str(run_dir)]


def _fatigue_done(run_dir: Path) -> bool:
    return isinstance(read_json(run_dir / "fatigue" / "summary.json"), dict)


def run_ok(run_dir: Path, fingerprint: str) -> bool:
    """An ok run in ``run_dir`` of the scenario of ``fingerprint`` (point.json, summary.json)."""
    meta = read_json(run_dir / "point.json")
    summary = read_json(run_dir / "summary.json")
    return isinstance(meta, dict) and meta.get("fingerprint") == fingerprint and \
        isinstance(summary, dict) and summary.get("status") == "ok"


def point_state(p: Point, run_dir: Path, fatigue: bool) -> str:
    """``done``, ``fatigue`` (run ok, fatigue missing) or ``todo``."""
    if not run_ok(run_dir, p.fingerprint):
        return "todo"
    return "fatigue" if fatigue and not _fatigue_done(run_dir) else "done"


def run_outcome(code: int, run_dir: Path, log: Path, fatigue: bool) -> tuple[str, str]:
    """``("ok", "")``, ``("fatigue", "")`` (fatigue still to do) or ``("failed", why)``."""
    summary = read_json(run_dir / "summary.json")
    if code == 0 and isinstance(summary, dict) and summary.get("status") == "ok":
        return ("fatigue", "") if fatigue and not _fatigue_done(run_dir) else ("ok", "")
    err = summary.get("error", "") if isinstance(summary, dict) else ""
    err = err or _last_error(log)
    return "failed", f"run {_exit_text(code)}" + (f": {err}" if err else "")


def fatigue_outcome(code: int, run_dir: Path, log: Path) -> tuple[str, str]:
    """The fatigue phase ended with exit ``code``: ``("ok", "")`` or ``("failed", why)``."""
    if code == 0 and _fatigue_done(run_dir):
        return "ok", ""
    err = _last_error(log)
    return "failed", f"fatigue {_exit_text(code)}" + (f": {err}" if err else "")
