"""The local executor: the points of a validated sweep as ``suscosim run`` subprocesses on
this machine, ``jobs`` at a time, each followed by the fatigue worker when needed."""

from __future__ import annotations

import shutil
import signal
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TextIO

from cosim.journal import last_step

from ..cli_util import interrupt_on_sigterm
from . import phases
from .fork import Parent, keep_only_fork_checkpoint, parent_state
from .results import Display, event_line
from .spec import Point, Sweep, toml_value


@dataclass
class Job:
    point: Point
    run_dir: Path
    phase: str
    proc: subprocess.Popen
    t0: float
    log: Path
    fresh: bool = True  # its run was (re)done in this session (counts in the step progress)
    parent: Parent | None = None  # the parent run of a group ([sweep] fork_at), not a point

    def step(self) -> int | None:  # from the tail of its journal
        return last_step(self.run_dir / "journal.msgpack")


class Runner:
    def __init__(self, sweep: Sweep, out: Path, connect: list[str], external: list[str],
                 stream: TextIO) -> None:
        self.sweep, self.out = sweep, out
        self.connect, self.external = connect, external
        self.stream = stream
        self.status: dict[str, tuple[str, str]] = {}  # id -> (status, error) of this session
        self.plan = sweep.fork  # [sweep] fork_at: the parents and each point's fork
        self.parents = {pa.id: pa for pa in self.plan.parents} if self.plan else {}

    def run_dir(self, p: Point) -> Path:
        return self.sweep.run_dir(self.out, p)

    def _start_run(self, p: Point, parent: Parent | None = None) -> Job:
        """A point's run (a fork of its group's parent with fork_at), or a ``parent``'s."""
        d = self.run_dir(p) if parent is None else self.plan.parent_dir(self.out, parent)
        meta = phases.point_meta(self.sweep.name, p.id, p.params, str(p.base), p.overrides,
                                 p.fingerprint)
        phases.prepare_run_dir(d, meta, phases.this_worker("local"))
        log = d / "sweep.log"
        if self.plan is not None and parent is None:
            cmd = phases.run_command(["--fork", self.plan.spec(self.out, p)], d,
                                     [*self.plan.fork_sets[p.id], f"run.id={toml_value(p.run_id)}"],
                                     self.sweep.jobs > 1, self.connect)
        else:
            cmd = phases.run_command([str(p.base)], d, p.set_args, self.sweep.jobs > 1,
                                     self.connect, self.external)
        return Job(p, d, "run", phases.start(cmd, log), time.monotonic(), log, parent=parent)

    def _start_fatigue(self, p: Point) -> Job:
        d = self.run_dir(p)
        shutil.rmtree(d / "fatigue", ignore_errors=True)
        log = d / "fatigue.log"
        proc = phases.start(phases.fatigue_command(d), log)
        return Job(p, d, "fatigue", proc, time.monotonic(), log)

    def _finish(self, job: Job) -> Job | None:
        """A process ended: record the point's outcome, or return its next phase."""
        code = job.proc.returncode
        if code != 0:
            phases.kill_group(job.proc)  # nodes orphaned by a killed run
        p = job.point
        if job.parent is not None:  # a parent: ok when its checkpoint at k is complete
            st, err = phases.run_outcome(code, job.run_dir, job.log, False)
            if st == "ok" and parent_state(job.parent, job.run_dir) != "done":
                st, err = "failed", f"no complete checkpoint at k = {job.parent.k}"
            if st == "ok":
                keep_only_fork_checkpoint(job.parent, job.run_dir)
        elif job.phase == "run":
            st, err = phases.run_outcome(code, job.run_dir, job.log, self.sweep.fatigue)
            if st == "fatigue":
                return self._start_fatigue(p)
        else:
            st, err = phases.fatigue_outcome(code, job.run_dir, job.log)
        self.status[p.id] = (st, err)
        return None

    def _order(self, queue: list[tuple[Point, str]]) -> None:
        """Parents first (they hold forks back), then the longest runs, then fatigue."""
        queue.sort(key=lambda ps: (0, -ps[0].n_steps) if ps[1] == "parent" else
                   (1, -ps[0].n_steps) if ps[1] == "todo" else (2, 0))

    def execute(self, todo: list[tuple[Point, str]]) -> bool:
        """Run the points (a fork after its parent); False if interrupted."""
        queue = list(todo)
        waiting: dict[str, list[tuple[Point, str]]] = {}  # parent id -> its forks to run
        if self.plan is not None:
            queue = [ps for ps in todo if ps[1] != "todo"]
            for p, st in (ps for ps in todo if ps[1] == "todo"):
                parent = self.plan.parent_of[p.id]
                if parent_state(parent, self.plan.parent_dir(self.out, parent)) == "done":
                    queue.append((p, st))
                else:
                    waiting.setdefault(parent.id, []).append((p, st))
            queue += [(self.parents[pid].point, "parent") for pid in waiting]
        # longest first: the sweep ends sooner when the long runs do not start last
        self._order(queue)
        todo_state = {p.id: st for p, st in todo}
        n_total = len(todo) + len(waiting)
        display = Display(self.stream, n_total,
                          sum(p.n_steps for p, st in queue if st in ("todo", "parent")) +
                          sum(p.n_steps for w in waiting.values() for p, _ in w))
        jobs: list[Job] = []
        interrupted = False

        old = interrupt_on_sigterm()
        finished = failed = steps_done = 0
        try:
            while queue or jobs:
                while queue and len(jobs) < self.sweep.jobs:
                    p, state = queue.pop(0)
                    job = (self._start_fatigue(p) if state == "fatigue" else
                           self._start_run(p, self.parents[p.id] if state == "parent" else None))
                    job.fresh = state != "fatigue"
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
                    st, err = self.status[job.point.id]
                    failed += st != "ok"
                    display.event(event_line(job.run_dir, job.point.id, st, err, finished, n_total))
                    if job.parent is not None:
                        steps_done += job.point.n_steps
                        forks = waiting.pop(job.point.id, [])
                        if st == "ok":
                            queue += forks
                            self._order(queue)
                        for p, _ in forks if st != "ok" else []:
                            self.status[p.id] = ("failed", f"its parent run {job.point.id} "
                                                 f"failed: {err}")
                            finished += 1
                            failed += 1
                            steps_done += p.n_steps
                            display.event(event_line(self.run_dir(p), p.id, "failed",
                                                     self.status[p.id][1], finished, n_total))
                        continue
                    steps_done += job.point.n_steps if todo_state[job.point.id] == "todo" else 0
                jobs = still
                display.update(jobs, finished, failed,
                               len(queue) + sum(len(w) for w in waiting.values()), steps_done)
                time.sleep(0.25)
        except KeyboardInterrupt:
            interrupted = True
            display.close()
            for job in jobs:
                phases.kill_group(job.proc)
            deadline = time.monotonic() + 5.0
            for job in jobs:
                try:
                    job.proc.wait(timeout=max(0.1, deadline - time.monotonic()))
                except subprocess.TimeoutExpired:
                    phases.kill_group(job.proc, signal.SIGKILL)
                    job.proc.wait()
                self.status[job.point.id] = ("failed", "interrupted")
        finally:
            signal.signal(signal.SIGTERM, old)
            display.close()
        return not interrupted
