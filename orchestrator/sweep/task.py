"""One sweep point run whole on a Dask worker (:func:`run_point`): ``suscosim run`` there,
then the fatigue worker if wanted; the run folder goes back as a tar.gz (or is written under a
shared ``runs_dir``). The scenario travels whole (paths under the client's project folder
rewritten to the worker's), so only the data files it names must be there.
"""

from __future__ import annotations

import ctypes
import io
import shutil
import signal
import subprocess
import tarfile
import tempfile
import time
from pathlib import Path
from typing import Any

from cosim.journal import last_step
from cosim.run_folder import read_json

from . import phases

POLL_S = 0.5
PROGRESS_S = 1.0


def pack(run_dir: Path) -> bytes:
    """A run folder as tar.gz bytes (members relative to the folder)."""
    buf = io.BytesIO()
    with tarfile.open(fileobj=buf, mode="w:gz", compresslevel=1) as tar:
        for f in sorted(run_dir.rglob("*")):
            tar.add(f, arcname=str(f.relative_to(run_dir)), recursive=False)
    return buf.getvalue()


def unpack(data: bytes, run_dir: Path) -> None:
    """Replace ``run_dir`` by the folder packed in ``data``."""
    if run_dir.exists():
        shutil.rmtree(run_dir)
    run_dir.mkdir(parents=True)
    with tarfile.open(fileobj=io.BytesIO(data), mode="r:gz") as tar:
        tar.extractall(run_dir, filter="data")


def _die_with_parent() -> None:  # runs in the child between fork and exec
    try:  # Linux: SIGTERM when the worker thread that started us dies (a killed worker)
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


class _Cancelled(Exception):
    pass


class _Context:

    def __init__(self, task: dict[str, Any]) -> None:
        from distributed import get_worker

        self.worker = get_worker()
        self.key = self.worker.get_current_task()
        self.topic, self.id = task["topic"], task["point"]["id"]
        self.info = phases.this_worker("dask", address=self.worker.address,
                                       name=str(self.worker.name))
        self.last = 0.0

    def cancelled(self) -> bool:
        ts = self.worker.state.tasks.get(self.key)
        return ts is None or ts.state in ("cancelled", "released", "forgotten")

    def emit(self, phase: str, k: int | None = None, force: bool = False) -> None:
        now = time.monotonic()
        if force or now - self.last >= PROGRESS_S:
            self.last = now
            self.worker.log_event(self.topic, {"id": self.id, "phase": phase, "k": k,
                                               "by": self.info})

    def wait(self, proc: subprocess.Popen, phase: str, run_dir: Path) -> int:
        """Wait for a phase's process, reporting the run's step; kill it if cancelled."""
        while proc.poll() is None:
            if self.cancelled():
                phases.kill_group(proc)
                try:
                    proc.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    phases.kill_group(proc, signal.SIGKILL)
                    proc.wait()
                raise _Cancelled
            if phase == "run":
                self.emit(phase, last_step(run_dir / "journal.msgpack"))
            time.sleep(POLL_S)
        if proc.returncode != 0:
            phases.kill_group(proc)  # nodes orphaned by a killed run
        return int(proc.returncode)


def _remap(text: str, root: str) -> str:
    return text.replace(root, str(phases.ROOT)) if root and root != str(phases.ROOT) else text


def run_point(task: dict[str, Any]) -> dict[str, Any]:
    """Run one sweep point (``task``: :func:`task_doc`) on this Dask worker: ``id``, ``status``
    (ok|failed|cancelled), ``error``, ``worker``, ``archive`` (tar.gz bytes or None). A failed
    run is a result, not an exception: Dask retries only a point whose worker was lost."""
    ctx = _Context(task)
    pid, root = ctx.id, task["root"]
    shared = task.get("runs_dir")
    scratch = Path(tempfile.mkdtemp(prefix="suscosim-", dir=ctx.worker.local_directory))
    run_dir = Path(_remap(shared, root)) / pid if shared else scratch / pid
    result: dict[str, Any] = {"id": pid, "status": "failed", "error": "", "worker": ctx.info,
                              "archive": None}
    try:
        phase = task["phase"]
        if phase == "todo":
            phases.prepare_run_dir(run_dir, task["point"], ctx.info)
            ctx.emit("run", force=True)
            scenario = scratch / f"{pid}.toml"  # the point's scenario, whole
            scenario.write_text(_remap(task["scenario"], root))
            cmd = phases.run_command([str(scenario)], run_dir, [], pin_off=True)
            code = ctx.wait(phases.start(cmd, run_dir / "sweep.log", _die_with_parent), "run",
                            run_dir)
            st, err = phases.run_outcome(code, run_dir, run_dir / "sweep.log", task["fatigue"])
            phase = "fatigue" if st == "fatigue" else "done"
        else:
            if task.get("archive"):
                unpack(task["archive"], run_dir)
            meta = read_json(run_dir / "point.json") or dict(task["point"])
            phases.write_point_json(run_dir, {**meta, "fatigue_worker": ctx.info})
            st, err = "failed", ""
        if phase == "fatigue":
            ctx.emit("fatigue", force=True)
            shutil.rmtree(run_dir / "fatigue", ignore_errors=True)
            log = run_dir / "fatigue.log"
            proc = phases.start(phases.fatigue_command(run_dir), log, _die_with_parent)
            code = ctx.wait(proc, "fatigue", run_dir)
            st, err = phases.fatigue_outcome(code, run_dir, log)
        result.update(status=st, error=err)
        if not shared:
            result["archive"] = pack(run_dir)
        return result
    except _Cancelled:
        return {**result, "status": "cancelled", "error": "cancelled"}
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def scenario_toml(scenario: dict[str, Any]) -> str:
    """A loaded scenario as a TOML file's text (one inline table per section)."""
    from .spec import toml_value

    return "".join(f"{name} = {toml_value(section)}\n" for name, section in scenario.items())


def task_doc(point_json: dict[str, Any], scenario: dict[str, Any], phase: str, fatigue: bool,
             runs_dir: Path | None, run_dir: Path, topic: str) -> dict[str, Any]:
    """The task of one point for :func:`run_point`: its point.json, scenario (TOML, paths
    absolute), phase, fatigue, shared runs_dir, archive (fatigue phase), root, topic."""
    archive = None
    if phase == "fatigue" and runs_dir is None:
        archive = pack(run_dir)
    return {"point": point_json, "scenario": scenario_toml(scenario), "phase": phase,
            "fatigue": fatigue, "runs_dir": str(runs_dir) if runs_dir else None,
            "archive": archive, "root": str(phases.ROOT), "topic": topic}
