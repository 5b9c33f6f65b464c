"""The Dask executor (``--executor dask --scheduler tcp://HOST:8786``): every point is one task
(:func:`.task.run_point`) run whole on a worker; Dask schedules and retries a point whose worker
was lost. A finished point's folder comes back in the result (or is in the shared
``runs_dir``); progress comes as Dask events on this session's topic.
"""

from __future__ import annotations

import re
import signal
import threading
import time
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO

from cosim import scenario as sc
from cosim.errors import SuscosimError

from ..cli_util import interrupt_on_sigterm
from .phases import point_meta
from .results import Display, event_line
from .spec import Point, Sweep
from .task import run_point, task_doc, unpack


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
        meta = point_meta(self.sweep.name, p.id, p.params, str(p.base), p.overrides, p.fingerprint)
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
            try:
                self.client.unsubscribe_topic(topic)
            except Exception:  # noqa: BLE001 - the scheduler may be gone
                pass
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
