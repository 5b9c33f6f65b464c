"""The Dask executor (``--executor dask --scheduler tcp://HOST:8786``): every point is one task,
:func:`run_point` (``suscosim run`` on the worker, then the fatigue worker if wanted), run whole
on a worker; Dask schedules and retries a point whose worker was lost. The scenario travels
whole (paths under the client's project folder rewritten to the worker's); the run folder comes
back as a tar.gz (or is written under a shared ``runs_dir``); progress comes as Dask events.
"""

from __future__ import annotations

import ctypes
import io
import re
import shutil
import signal
import subprocess
import tarfile
import tempfile
import threading
import time
import uuid
from contextlib import suppress
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO

from cosim import scenario as sc
from cosim.errors import SuscosimError
from cosim.journal import last_step
from cosim.run_folder import read_json

from ..cli_util import interrupt_on_sigterm
from . import phases
from .results import Display, event_line
from .spec import Point, Sweep

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
    if run_dir.exists():
        shutil.rmtree(run_dir)
    run_dir.mkdir(parents=True)
    with tarfile.open(fileobj=io.BytesIO(data), mode="r:gz") as tar:
        tar.extractall(run_dir, filter="data")


def _die_with_parent() -> None:
    """In the child between fork and exec (Linux): SIGTERM when the worker thread that started
    us dies (a killed worker)."""
    with suppress(OSError, AttributeError):
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG


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


class DaskError(SuscosimError):
    """Dask is missing or its scheduler cannot be reached (exit code 2)."""

    exit_code = 2


@dataclass
class RemoteJob:
    point: Point
    phase: str
    t0: float
    worker: str
    k: int | None = None
    fresh: bool = True

    def step(self) -> int | None:
        return self.k


ADDRESS = re.compile(r"((tcp|tls|ws|wss|ucx)://)?(\[[0-9a-fA-F:.]+\]|[A-Za-z0-9_.-]+)(:\d{1,5})?")


def connect(address: str, timeout_s: float = 20.0) -> Any:
    """A ``distributed.Client`` of the scheduler at ``address``; DaskError if it fails."""
    if not ADDRESS.fullmatch(address):
        raise DaskError(f"--scheduler {address!r}: expected a Dask scheduler address such as "
                        "tcp://HOST:8786")
    try:
        from distributed import Client
    except ImportError:
        raise DaskError("--executor dask needs the 'distributed' package "
                        "(python3 -m pip install 'dask[distributed]')") from None
    try:
        # results through the scheduler: workers may sit on networks the client cannot reach
        return Client(address, timeout=f"{timeout_s}s", set_as_default=False,
                      direct_to_workers=False)
    except (OSError, TimeoutError, ValueError) as exc:
        raise DaskError(f"--scheduler {address}: cannot reach the Dask scheduler "
                        f"({type(exc).__name__}: {exc}); start one with 'suscosim cluster' "
                        "or 'dask scheduler'") from None


class DaskRunner:
    """Runs the points as Dask tasks (the interface of :class:`.local.Runner`)."""

    def __init__(self, sweep: Sweep, out: Path, scheduler: str, stream: TextIO) -> None:
        self.sweep, self.out, self.scheduler = sweep, out, scheduler
        self.stream = stream
        self.status: dict[str, tuple[str, str]] = {}
        self.client = connect(scheduler)
        self._lock = threading.Lock()
        self._events: list[dict[str, Any]] = []

    def _on_event(self, event: Any) -> None:  # in the client's event-loop thread
        msg = event[1] if isinstance(event, tuple) and len(event) == 2 else event
        if isinstance(msg, dict):
            with self._lock:
                self._events.append(msg)

    def _task(self, p: Point, phase: str, topic: str) -> dict[str, Any]:
        meta = phases.point_meta(self.sweep.name, p.id, p.params, str(p.base), p.overrides,
                                 p.fingerprint)
        scenario = sc.load(p.base, p.set_args)  # as validate_points loaded it
        return task_doc(meta, scenario, phase, self.sweep.fatigue, self.sweep.runs_dir,
                        self.sweep.run_dir(self.out, p), topic)

    def workers_text(self) -> str:
        info = self.client.scheduler_info()
        ws = info.get("workers", {})
        threads = sum(int(w.get("nthreads", 0)) for w in ws.values())
        return f"{len(ws)} Dask workers ({threads} threads) at {self.scheduler}"

    def execute(self, todo: list[tuple[Point, str]]) -> bool:
        token = uuid.uuid4().hex[:8]
        topic = f"suscosim-sweep-{self.sweep.name}-{token}"
        self.client.subscribe_topic(topic, self._on_event)
        display = Display(self.stream, len(todo), sum(p.n_steps for p, st in todo if st == "todo"))
        points = {p.id: (p, st) for p, st in todo}
        futures: dict[Any, str] = {}
        running: dict[str, RemoteJob] = {}
        finished = failed = steps_done = 0
        interrupted = False

        old = interrupt_on_sigterm()
        try:
            for p, st in sorted(todo, key=lambda ps: -ps[0].n_steps):  # longest first
                fut = self.client.submit(run_point, self._task(p, st, topic),
                                         key=f"suscosim-{p.id}-{token}", pure=False,
                                         priority=p.n_steps)
                futures[fut] = p.id
            pending = set(futures)
            while pending:
                self._drain(running, display)
                for fut in [f for f in pending if f.done()]:
                    pending.discard(fut)
                    pid = futures[fut]
                    st, err = self._collect(fut, points[pid][0])
                    self.status[pid] = (st, err)
                    running.pop(pid, None)
                    finished += 1
                    failed += st != "ok"
                    steps_done += points[pid][0].n_steps if points[pid][1] == "todo" else 0
                    display.event(event_line(self.sweep.run_dir(self.out, points[pid][0]),
                                             pid, st, err, finished, len(todo)))
                display.update(list(running.values()), finished, failed,
                               len(pending) - len(running), steps_done)
                time.sleep(0.25)
        except KeyboardInterrupt:
            interrupted = True
            display.close()
            self.client.cancel(list(futures))  # the tasks stop their runs
            for pid in futures.values():
                if pid not in self.status:
                    self.status[pid] = ("failed", "interrupted")
        finally:
            signal.signal(signal.SIGTERM, old)
            display.close()
            with suppress(Exception):  # noqa: BLE001 - the scheduler may be gone
                self.client.unsubscribe_topic(topic)
            self.client.close()
        return not interrupted

    def _drain(self, running: dict[str, RemoteJob], display: Display) -> None:
        with self._lock:
            events, self._events = self._events, []
        for ev in events:
            pid, worker = ev.get("id"), ev.get("by")
            if not isinstance(worker, dict):
                continue
            name = str(worker.get("name") or worker.get("address"))
            if pid is None:
                continue
            job = running.get(pid)
            if job is None or job.worker != name or job.phase != ev.get("phase"):
                if job is not None and job.worker != name:
                    display.event(f"  {pid}: started again on worker {name} (worker "
                                  f"{job.worker} lost)")
                p = next((p for p in self.sweep.points if p.id == pid), None)
                if p is None:
                    continue
                job = RemoteJob(p, str(ev.get("phase")), time.monotonic(), name)
                running[pid] = job
            if ev.get("k") is not None:
                job.k = int(ev["k"])

    def _collect(self, fut: Any, p: Point) -> tuple[str, str]:
        if fut.status != "finished":
            exc = fut.exception()
            return "failed", f"dask task {fut.status}: {type(exc).__name__}: {exc}"
        res = fut.result()
        if res.get("archive"):
            unpack(res["archive"], self.sweep.run_dir(self.out, p))
        return str(res.get("status")), str(res.get("error") or "")
