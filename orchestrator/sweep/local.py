"""The local executor: the points of a validated sweep as ``suscosim run`` subprocesses on
this machine, ``jobs`` at a time, each followed by the fatigue worker when needed."""

from __future__ import annotations

import json
import shutil
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TextIO

from .display import Display
from .procs import _exit_text, _kill_group, _last_error, _start
from .results import _fmt
from .spec import Point, Sweep
from .state import _read_json


@dataclass
class Job:
    """A point being worked on: its phase (run, fatigue) and process."""

    point: Point
    run_dir: Path
    phase: str
    proc: subprocess.Popen
    t0: float
    log: Path
    fresh: bool = True  # its run was (re)done in this session (counts in the step progress)



class Runner:
    """Runs the points of a validated sweep, ``jobs`` at a time."""

    def __init__(self, sweep: Sweep, out: Path, connect: list[str], external: list[str],
                 stream: TextIO) -> None:
        self.sweep, self.out = sweep, out
        self.connect, self.external = connect, external
        self.stream = stream
        self.status: dict[str, tuple[str, str]] = {}  # id -> (status, error) of this session

    def run_dir(self, p: Point) -> Path:
        return self.out / "runs" / p.id

    def _run_cmd(self, p: Point) -> list[str]:
        cmd = [sys.executable, "-m", "orchestrator", "run", str(p.base),
               "--out", str(self.run_dir(p)), "--quiet"]
        if self.sweep.jobs > 1:  # runs side by side: pinning each to the same cores hurts
            cmd += ["--pin", "off"]
        for s in p.set_args:
            cmd += ["--set", s]
        for ep in self.connect:
            cmd += ["--connect", ep]
        for n in self.external:
            cmd += ["--external", n]
        return cmd

    def _start_run(self, p: Point) -> Job:
        d = self.run_dir(p)
        if d.exists():  # a failed or stale attempt: start clean
            shutil.rmtree(d)
        d.mkdir(parents=True)
        (d / "point.json").write_text(json.dumps(
            {"sweep": self.sweep.name, "id": p.id, "params": p.params, "base": str(p.base),
             "overrides": p.overrides, "fingerprint": p.fingerprint}, indent=2, default=str))
        log = d / "sweep.log"
        return Job(p, d, "run", _start(self._run_cmd(p), log), time.monotonic(), log)

    def _start_fatigue(self, p: Point) -> Job:
        d = self.run_dir(p)
        shutil.rmtree(d / "fatigue", ignore_errors=True)
        log = d / "fatigue.log"
        cmd = [sys.executable, "-m", "orchestrator", "fatigue", str(d)]
        return Job(p, d, "fatigue", _start(cmd, log), time.monotonic(), log)

    def _finish(self, job: Job) -> Job | None:
        """A process ended: record the point's outcome, or return its next phase."""
        code = job.proc.returncode
        if code != 0:
            _kill_group(job.proc)  # nodes orphaned by a killed run
        p = job.point
        if job.phase == "run":
            summary = _read_json(job.run_dir / "summary.json")
            if code == 0 and isinstance(summary, dict) and summary.get("status") == "ok":
                live = _read_json(job.run_dir / "fatigue" / "summary.json")
                if self.sweep.fatigue and not isinstance(live, dict):  # no live fatigue node
                    return self._start_fatigue(p)
                self.status[p.id] = ("ok", "")
                return None
            err = summary.get("error", "") if isinstance(summary, dict) else ""
            err = err or _last_error(job.log)
            self.status[p.id] = ("failed", f"run {_exit_text(code)}" + (f": {err}" if err
                                                                           else ""))
            return None
        if code == 0 and isinstance(_read_json(job.run_dir / "fatigue" / "summary.json"), dict):
            self.status[p.id] = ("ok", "")
        else:
            err = _last_error(job.log)
            self.status[p.id] = ("failed", f"fatigue {_exit_text(code)}" + (f": {err}" if err
                                                                               else ""))
        return None

    def execute(self, todo: list[tuple[Point, str]]) -> bool:
        """Run the given points (``todo`` or ``fatigue`` phase); False if interrupted."""
        # longest first: the sweep ends sooner when the long runs do not start last
        queue = sorted(todo, key=lambda ps: -ps[0].n_steps if ps[1] == "todo" else 0)
        todo_state = {p.id: st for p, st in todo}
        display = Display(self.stream, len(todo),
                          sum(p.n_steps for p, st in todo if st == "todo"))
        jobs: list[Job] = []
        interrupted = False

        def on_signal(signum, frame):  # noqa: ARG001
            raise KeyboardInterrupt

        old = signal.signal(signal.SIGTERM, on_signal)
        finished = failed = steps_done = 0
        try:
            while queue or jobs:
                while queue and len(jobs) < self.sweep.jobs:
                    p, state = queue.pop(0)
                    job = self._start_run(p) if state == "todo" else self._start_fatigue(p)
                    job.fresh = state == "todo"
                    jobs.append(job)
                still: list[Job] = []
                for job in jobs:
                    if job.proc.poll() is None:
                        still.append(job)
                        continue
                    nxt = self._finish(job)
                    if nxt is not None:
                        still.append(nxt)
                        continue
                    finished += 1
                    steps_done += job.point.n_steps if todo_state[job.point.id] == "todo" else 0
                    st, err = self.status[job.point.id]
                    failed += st != "ok"
                    display.event(self._event_line(job.point, st, err, finished,
                                                   len(todo)))
                jobs = still
                display.update(jobs, finished, failed, len(queue), steps_done)
                time.sleep(0.25)
        except KeyboardInterrupt:
            interrupted = True
            display.close()
            for job in jobs:
                _kill_group(job.proc)
            deadline = time.monotonic() + 5.0
            for job in jobs:
                try:
                    job.proc.wait(timeout=max(0.1, deadline - time.monotonic()))
                except subprocess.TimeoutExpired:
                    _kill_group(job.proc, signal.SIGKILL)
                    job.proc.wait()
                self.status[job.point.id] = ("failed", "interrupted")
        finally:
            signal.signal(signal.SIGTERM, old)
            display.close()
        return not interrupted

    def _event_line(self, p: Point, status: str, err: str, i: int, n: int) -> str:
        d = self.run_dir(p)
        head = f"[{i}/{n}] {status:<6} {p.id}"
        if status != "ok":
            return f"{head}: {err}"
        s = _read_json(d / "summary.json") or {}
        text = f"{head}  wall {s.get('wall_s', 0):.1f} s, {s.get('steps_per_s', 0):.0f} steps/s"
        f = _read_json(d / "fatigue" / "summary.json")
        if isinstance(f, dict):
            text += f", min life {_fmt(f.get('min_life_km'))} km"
        return text

