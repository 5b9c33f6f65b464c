"""``suscosim sweep SWEEP.toml``: a grid of scenarios, several runs at once, resumable.

    suscosim sweep SWEEP.toml [--out DIR] [--jobs N] [--connect EP] [--external NODE]
                              [--no-fatigue] [--list]
    suscosim sweep SWEEP.toml --serve NODE --connect EP     (on another machine)

A sweep file names a base scenario and a grid; every grid point is one run::

    [sweep]
    name = "ch6_pave"                    # default: the file's stem
    base = "../ch4_qvm_realistic_pave.toml"   # relative to the sweep file; a list = an axis
    jobs = 2                             # runs at once (default: cores // 2, at least 1)
    fatigue = true                       # fatigue worker on each finished run (default false)
    channels = ["plant/response/a_b"]    # channels in the results table (default: a few)
    [sweep.grid]                         # the axes; the points are their product
    "road.speed_kmh" = [30, 50]          # a dotted scenario key and its values
    [sweep.grid.strategy]                # an axis of named variants, each a set of overrides
    passive = { controller = { law = "passive", c = 3800.0, velocity = "damper" } }
    tss1 = { controller = { law = "tss1", preset = "realistic", velocity = "damper" } }
    [sweep.set]                          # fixed overrides for every point
    "run.h" = 0.001

Override keys are the dotted keys of ``suscosim run --set`` (quote them in TOML, or TOML
reads ``road.speed_kmh`` as a nested table); a table value replaces the whole table at its
key (``controller = {...}`` replaces the base's controller section). Relative file paths in
overrides (``road.path``, ``controller.curve``, ``fatigue.influence``) are relative to the
sweep file's folder.

Each point is ``suscosim run BASE --set ... --set run.id=<point id> --out DIR/runs/<point id>
--quiet`` in its own process group (a crashed run cannot take the sweep down), as many at
once as ``--jobs``. Its id is the sweep name and the point's values, so a restart finds it.

Sweep folder (``--out``, default ``sweeps/<name>``)::

    sweep.json      {"name", "base", "grid", "set", "points": [{"id", "params", "run_dir"}]}
    runs/<id>/      a run folder (+ point.json, sweep.log; fatigue/ when fatigue is on)
    results.csv     one row per point: id, params, status, error, timing, peaks/RMS, fatigue
    results.json    the same rows as a JSON list

Resumable: a point whose run folder holds ``summary.json`` with status ok (and
``fatigue/summary.json`` when fatigue is on) for the same resolved scenario is not redone;
a failed or unfinished one is; an ok run whose fatigue is missing gets only its fatigue.

Exit codes: 0 every point ok, 1 a point failed, 2 bad sweep file (nothing was started),
130 interrupted.
"""

from __future__ import annotations

import argparse
import copy
import csv
import hashlib
import itertools
import json
import math
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO

from cosim import scenario as sc
from cosim.errors import InputFileError, ScenarioError, SuscosimError
from cosim.keys import check_name

ROOT = Path(__file__).resolve().parents[1]
SWEEP_KEYS = ("name", "base", "jobs", "fatigue", "grid", "set", "channels", "description")
DEFAULT_CHANNELS = ("plant/response/a_b", "plant/response/a_w", "tyre_road/force/F_t",
                    "controller/force/F_d", "plant/arm/ball_joint_z")
FATIGUE_COLUMNS = ("life_repeats", "life_km", "max_damage", "critical_node")
MAX_ID = 64
RESERVED = ("base", "point", "status", "error", "wall_s", "steps_per_s", "n_steps", "run_dir",
            *FATIGUE_COLUMNS)
"""Names a grid axis cannot have (result columns, the base axis)."""


class SweepError(SuscosimError):
    """A bad sweep file or point (exit code 2); the message names the key or the point."""

    exit_code = 2


# --------------------------------------------------------------------------- sweep file

@dataclass
class Axis:
    """One grid axis: a parameter name and, per value, its label and overrides."""

    name: str
    labels: list[Any]
    overrides: list[dict[str, Any]]
    bases: list[Path] | None = None  # the ``base`` axis: one scenario file per label


@dataclass
class Point:
    """One grid point: one run."""

    index: int
    id: str
    params: dict[str, Any]
    base: Path
    overrides: dict[str, Any]
    n_steps: int = 0
    fingerprint: str = ""

    @property
    def set_args(self) -> list[str]:
        """The ``--set`` assignments of this point (the run id last)."""
        return [f"{k}={toml_value(v)}" for k, v in self.overrides.items()] + \
            [f"run.id={toml_value(self.id)}"]


@dataclass
class Sweep:
    """A parsed and checked sweep file (scenarios not yet validated)."""

    path: Path
    name: str
    bases: list[Path]
    axes: list[Axis]
    fixed: dict[str, Any]
    jobs: int
    fatigue: bool
    channels: list[str]
    raw_grid: dict[str, Any]
    points: list[Point] = field(default_factory=list)


def toml_value(v: Any) -> str:
    """A Python value (from TOML) as a TOML inline value, for ``--set``."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, list | tuple):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{json.dumps(str(k))} = {toml_value(x)}"
                               for k, x in v.items()) + "}"
    raise TypeError(f"cannot write {type(v).__name__} as a TOML value")


def _slug(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int | float):
        return repr(v)
    if isinstance(v, str):
        s = re.sub(r"[^A-Za-z0-9_.]+", "_", v).strip("_.")
        return s or "x"
    return "h" + hashlib.sha1(json.dumps(v, sort_keys=True).encode()).hexdigest()[:8]


def point_id(name: str, labels: list[Any]) -> str:
    """``<name>-<value>-<value>...``: letters, digits, ``_ . -``, at most 64 characters
    (longer ones are cut and end in a hash of the values)."""
    pid = "-".join([name, *(_slug(v) for v in labels)])
    if len(pid) > MAX_ID:
        digest = hashlib.sha1(json.dumps([name, labels], sort_keys=True,
                                         default=str).encode()).hexdigest()[:10]
        pid = pid[:MAX_ID - 11].rstrip("-_.") + "-" + digest
    return pid


def _check_override_key(where: str, key: Any, value: Any) -> None:
    if not isinstance(key, str) or not key:
        raise SweepError(f"{where}: override keys must be dotted scenario keys")
    parts = key.split(".")
    if not all(parts) or (len(parts) < 2 and not isinstance(value, dict)):
        raise ScenarioError(f"{where}.{key}", value,
                            "a dotted scenario key such as \"run.h\" (quoted in TOML), or a "
                            "section name with a table value")
    if parts[0] not in sc.SECTIONS:
        raise ScenarioError(f"{where}.{key}", value,
                            "a key in one of the sections " + ", ".join(sc.SECTIONS))


def _absolute_paths(overrides: dict[str, Any], folder: Path) -> dict[str, Any]:
    """Relative file paths among the overrides, made absolute against ``folder``."""
    out = copy.deepcopy(overrides)
    path_keys = {f"{s}.{k}" for s, k in sc.PATH_KEYS}
    for key, value in out.items():
        candidates: list[tuple[dict, str]] = []
        if key in path_keys:
            candidates.append((out, key))
        elif isinstance(value, dict):
            for s, k in sc.PATH_KEYS:
                if key == s:
                    candidates.append((value, k))
        for holder, k in candidates:
            v = holder.get(k)
            if isinstance(v, str) and v and v != "builtin" and \
                    not Path(v).expanduser().is_absolute():
                holder[k] = str(folder / Path(v).expanduser())
    return out


def load_sweep(path: str | Path, jobs: int | None = None,
               fatigue: bool | None = None) -> Sweep:
    """Read and check a sweep file and enumerate its points (scenarios not yet validated)."""
    import tomllib

    path = Path(path)
    try:
        data = tomllib.loads(path.read_text())
    except OSError as exc:
        raise InputFileError(str(path), f"cannot read sweep file ({exc.strerror})") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputFileError(str(path), f"not valid TOML: {exc}") from None
    sw = data.get("sweep")
    if not isinstance(sw, dict):
        raise ScenarioError("sweep", sw, "a [sweep] table (with base and grid)")
    for k in sw:
        if k not in SWEEP_KEYS:
            raise ScenarioError(f"sweep.{k}", sw[k], "one of " + ", ".join(SWEEP_KEYS))
    folder = path.resolve().parent
    name = sw.get("name", path.stem)
    check_name("sweep.name", name)
    if len(name) > 40:
        raise ScenarioError("sweep.name", name, "at most 40 characters")
    raw_base = sw.get("base", None)
    if raw_base is None:  # the sweep file is its own base scenario
        if not any(k != "sweep" for k in data):
            raise ScenarioError("sweep.base", None, "a base scenario file (or scenario "
                                "sections in the sweep file itself)")
        bases = [path.resolve()]
    else:
        items = raw_base if isinstance(raw_base, list) else [raw_base]
        if not items or not all(isinstance(b, str) and b for b in items):
            raise ScenarioError("sweep.base", raw_base, "a scenario file or a list of them")
        bases = []
        for b in items:
            p = Path(b).expanduser()
            p = p if p.is_absolute() else folder / p
            if not p.is_file():
                raise InputFileError(str(p), "base scenario not found (sweep.base is "
                                     "relative to the sweep file)")
            bases.append(p.resolve())
    if jobs is None:
        jobs = sw.get("jobs", max(1, (os.cpu_count() or 2) // 2))
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise ScenarioError("sweep.jobs", jobs, "an integer >= 1")
    if fatigue is None:
        fatigue = sw.get("fatigue", False)
    if not isinstance(fatigue, bool):
        raise ScenarioError("sweep.fatigue", fatigue, "true or false")
    channels = sw.get("channels", list(DEFAULT_CHANNELS))
    if not isinstance(channels, list) or not all(isinstance(c, str) for c in channels):
        raise ScenarioError("sweep.channels", channels, "a list of channel names")
    fixed = sw.get("set", {})
    if not isinstance(fixed, dict):
        raise ScenarioError("sweep.set", fixed, "a table of dotted keys and values")
    for k, v in fixed.items():
        _check_override_key("sweep.set", k, v)
    grid = sw.get("grid", {})
    if not isinstance(grid, dict):
        raise ScenarioError("sweep.grid", grid, "a table of axes")
    axes: list[Axis] = []
    if len(bases) > 1:
        axes.append(Axis("base", [b.stem for b in bases], [{} for _ in bases], bases))
    for key, spec in grid.items():
        where = f"sweep.grid.{key}"
        if key in RESERVED:
            raise ScenarioError(where, spec, "an axis name other than " + ", ".join(RESERVED))
        if isinstance(spec, list):
            if not spec:
                raise ScenarioError(where, spec, "a non-empty list of values")
            _check_override_key("sweep.grid", key, spec[0])
            axes.append(Axis(key, list(spec), [{key: v} for v in spec]))
        elif isinstance(spec, dict):
            if not spec:
                raise ScenarioError(where, spec, "a non-empty table of named variants")
            labels, overrides = [], []
            for vname, ov in spec.items():
                if not isinstance(ov, dict) or not ov:
                    raise ScenarioError(f"{where}.{vname}", ov,
                                        "a table of overrides, e.g. { \"run.h\" = 0.001 }")
                for k, v in ov.items():
                    _check_override_key(f"{where}.{vname}", k, v)
                labels.append(vname)
                overrides.append(ov)
            axes.append(Axis(key, labels, overrides))
        else:
            raise ScenarioError(where, spec, "a list of values or a table of named variants")
    sweep = Sweep(path=path, name=name, bases=bases, axes=axes, fixed=fixed, jobs=jobs,
                  fatigue=fatigue, channels=channels, raw_grid=grid)
    seen: dict[str, int] = {}
    for index, combo in enumerate(itertools.product(*(range(len(a.labels)) for a in axes))):
        params: dict[str, Any] = {}
        overrides: dict[str, Any] = dict(fixed)
        base = bases[0]
        for axis, i in zip(axes, combo, strict=True):
            params[axis.name] = axis.labels[i]
            overrides.update(axis.overrides[i])
            if axis.bases is not None:
                base = axis.bases[i]
        pid = point_id(name, [params[a.name] for a in axes])
        if pid in seen:  # two values with the same slug (e.g. "a b" and "a_b")
            pid = point_id(name, [*(params[a.name] for a in axes), index])
        seen[pid] = index
        sweep.points.append(Point(index, pid, params, base,
                                  _absolute_paths(overrides, path.resolve().parent)))
    return sweep


def validate_points(sweep: Sweep, out: Path) -> None:
    """Load and preflight every point's scenario (``cosim.scenario.load`` with the point's
    overrides, then the runner's model checks); fills n_steps and the fingerprint. Raises
    SweepError naming the point and the key; starts nothing."""
    from .runner import resolve

    for p in sweep.points:
        try:
            scenario = sc.load(p.base, p.set_args)
            p.fingerprint = hashlib.sha256(json.dumps(scenario, sort_keys=True, default=str)
                                           .encode()).hexdigest()[:16]
            resolved = resolve(copy.deepcopy(scenario), out / "runs" / p.id)
            p.n_steps = int(resolved["run"]["n_steps"])
        except SuscosimError as exc:
            raise SweepError(f"sweep point '{p.id}' ({_params_text(p.params)}): {exc}") \
                from None


def _params_text(params: dict[str, Any]) -> str:
    return ", ".join(f"{k}={v}" for k, v in params.items()) or "no parameters"


# --------------------------------------------------------------------------- run folders

def _read_json(path: Path) -> Any:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


def point_state(p: Point, run_dir: Path, fatigue: bool) -> str:
    """``done``, ``fatigue`` (run ok, fatigue missing) or ``todo``."""
    meta = _read_json(run_dir / "point.json")
    summary = _read_json(run_dir / "summary.json")
    if not isinstance(meta, dict) or meta.get("fingerprint") != p.fingerprint or \
            not isinstance(summary, dict) or summary.get("status") != "ok":
        return "todo"
    if fatigue and not isinstance(_read_json(run_dir / "fatigue" / "summary.json"), dict):
        return "fatigue"
    return "done"


def journal_step(path: Path, tail_bytes: int = 32768) -> int | None:
    """The step index of the last intact record of a run journal that carries one (cheap:
    reads its tail with the journal reader every command uses), or None."""
    import msgpack

    from nodes.recorder.journal import read_journal

    try:
        records = read_journal(path, tail_bytes=tail_bytes).records
    except (OSError, ValueError):
        return None
    for _channel, raw in reversed(records):
        try:
            msg = msgpack.unpackb(raw, raw=False)
        except Exception:
            continue
        if isinstance(msg, dict) and isinstance(msg.get("k"), int):
            return int(msg["k"])
    return None


# --------------------------------------------------------------------------- execution

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


def _child_env() -> dict[str, str]:
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), *filter(None, [env.get("PYTHONPATH")])])
    return env


def _start(cmd: list[str], log: Path) -> subprocess.Popen:
    with open(log, "ab") as fh:
        return subprocess.Popen(cmd, stdout=fh, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL, env=_child_env(),
                                start_new_session=True)


def _kill_group(proc: subprocess.Popen, sig: int = signal.SIGTERM) -> None:
    """Signal the process group of one of our children (its node processes too)."""
    try:
        os.killpg(proc.pid, sig)
    except (ProcessLookupError, PermissionError):
        pass


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


class Display:
    """One progress display for the whole sweep: a line per running point, redrawn in place
    on a terminal; on a pipe, a line per event and a status line now and then."""

    def __init__(self, stream: TextIO, total: int, n_steps_total: int) -> None:
        self.stream, self.total = stream, total
        self.tty = stream.isatty()
        self.lines = 0
        self.t0 = time.monotonic()
        self.last_status = self.t0
        self.n_steps_total = max(1, n_steps_total)

    def _clear(self) -> None:
        if self.tty and self.lines:
            self.stream.write(f"\x1b[{self.lines}F\x1b[J")
            self.lines = 0

    def event(self, text: str) -> None:
        self._clear()
        self.stream.write(text + "\n")
        self.stream.flush()

    def update(self, jobs: list[Job], done: int, failed: int, pending: int,
               steps_done: int) -> None:
        elapsed = time.monotonic() - self.t0
        if not self.tty and time.monotonic() - self.last_status < 30.0:
            return
        steps = steps_done + sum((self._k(j) or 0) if j.phase == "run" else j.point.n_steps
                                 for j in jobs if j.phase == "run" or j.fresh)
        head = (f"sweep: {done}/{self.total} finished ({failed} failed), {len(jobs)} running, "
                f"{pending} waiting; {100 * min(1.0, steps / self.n_steps_total):3.0f}% of "
                f"the steps, {elapsed:5.0f} s")
        if not self.tty:
            self.last_status = time.monotonic()
            parts = [f"{j.point.id} {self._frac(j)}" for j in jobs]
            self.stream.write(head + (": " + ", ".join(parts) if parts else "") + "\n")
            self.stream.flush()
            return
        width = max((len(j.point.id) for j in jobs), default=0)
        rows = [head]
        for j in jobs:
            rows.append(f"  {j.point.id:<{width}}  {self._bar(j)}")
        self._clear()
        self.stream.write("\n".join(rows) + "\n")
        self.stream.flush()
        self.lines = len(rows)

    @staticmethod
    def _k(j: Job) -> int | None:
        return journal_step(j.run_dir / "journal.msgpack")

    def _frac(self, j: Job) -> str:
        if j.phase != "run":
            return j.phase
        k = self._k(j)
        return "starting" if k is None else f"{100 * k / max(1, j.point.n_steps):.0f}%"

    def _bar(self, j: Job) -> str:
        t = time.monotonic() - j.t0
        if j.phase != "run":
            return f"{j.phase:<8} {t:6.0f} s"
        k = self._k(j)
        if k is None:
            return f"starting {t:6.0f} s"
        n = max(1, j.point.n_steps)
        frac = min(1.0, max(0.0, k / n))
        fill = int(frac * 24)
        return (f"run [{'#' * fill}{'.' * (24 - fill)}] {100 * frac:5.1f}% step {k}/{n} "
                f"{t:6.0f} s")

    def close(self) -> None:
        self._clear()


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


# --------------------------------------------------------------------------- results

def _fmt(v: Any) -> str:
    if v is None or v == "":
        return ""
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def result_rows(sweep: Sweep, out: Path, status: dict[str, tuple[str, str]]) -> list[dict]:
    """One row per point, from the run folders (points of earlier sessions included)."""
    rows = []
    for p in sweep.points:
        d = out / "runs" / p.id
        summary = _read_json(d / "summary.json")
        summary = summary if isinstance(summary, dict) else {}
        fat = _read_json(d / "fatigue" / "summary.json") if sweep.fatigue else None
        if p.id in status:
            st, err = status[p.id]
        else:
            state = point_state(p, d, sweep.fatigue)
            st = "ok" if state == "done" else "failed"
            err = "" if st == "ok" else (summary.get("error") or "not run")
        row: dict[str, Any] = {"point": p.id, **p.params, "status": st, "error": err,
                               "wall_s": summary.get("wall_s"),
                               "steps_per_s": summary.get("steps_per_s"),
                               "n_steps": summary.get("n_steps", p.n_steps)}
        chans = summary.get("channels", {}) if isinstance(summary.get("channels"), dict) else {}
        for want in sweep.channels:
            names = [c for c in chans if c == want or c.startswith(want + "[")] or [want]
            for c in names:
                stats = chans.get(c, {})
                row[f"{c} peak"] = stats.get("peak")
                row[f"{c} rms"] = stats.get("rms")
        if sweep.fatigue:
            fat = fat if isinstance(fat, dict) and st == "ok" else {}  # not of a partial run
            row["life_repeats"] = fat.get("min_life_repeats")
            row["life_km"] = fat.get("min_life_km")
            row["max_damage"] = fat.get("max_damage_per_pass")
            row["critical_node"] = fat.get("critical_node_id")
        row["run_dir"] = f"runs/{p.id}"
        rows.append(row)
    return rows


def write_results(out: Path, rows: list[dict]) -> None:
    columns: list[str] = []
    for r in rows:
        columns += [c for c in r if c not in columns]
    columns = [c for c in columns  # a channel no run has (e.g. arm loads of a lumped car)
               if not c.endswith((" peak", " rms")) or any(r.get(c) is not None for r in rows)]
    rows = [{c: r.get(c) for c in columns} for r in rows]
    with open(out / "results.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=columns)
        w.writeheader()
        for r in rows:
            w.writerow({c: "" if r.get(c) is None else r.get(c) for c in columns})
    (out / "results.json").write_text(json.dumps(rows, indent=2, default=str))


def results_table(sweep: Sweep, rows: list[dict]) -> str:
    """The printed table: id, params, status, timing, the first channel's RMS, fatigue."""
    cols = ["point", *(a.name for a in sweep.axes), "status", "wall_s", "steps_per_s"]
    metrics = [c for c in (rows[0] if rows else {}) if c.endswith((" peak", " rms"))]
    extra = [c for c in metrics if any(r.get(c) is not None for r in rows)][:3]
    cols += extra
    if sweep.fatigue:
        cols += ["life_km", "life_repeats", "critical_node"]
    head = [c.split("/")[-1] if "/" in c else c for c in cols]
    body = [[_fmt(r.get(c)) for c in cols] for r in rows]
    widths = [max(len(h), *(len(b[i]) for b in body)) if body else len(h)
              for i, h in enumerate(head)]
    lines = ["  ".join(h.ljust(w) for h, w in zip(head, widths, strict=True))]
    lines.append("  ".join("-" * w for w in widths))
    lines += ["  ".join(v.ljust(w) for v, w in zip(b, widths, strict=True)) for b in body]
    errs = [f"  {r['point']}: {r['error']}" for r in rows if r["status"] != "ok" and r["error"]]
    if errs:
        lines += ["failed:", *errs]
    return "\n".join(lines)


def write_sweep_json(sweep: Sweep, out: Path) -> None:
    doc = {
        "name": sweep.name,
        "base": str(sweep.bases[0]) if len(sweep.bases) == 1 else [str(b) for b in sweep.bases],
        "grid": {a.name: a.labels for a in sweep.axes},
        "set": sweep.fixed,
        "fatigue": sweep.fatigue,
        "sweep_file": str(sweep.path.resolve()),
        "variants": {k: v for k, v in sweep.raw_grid.items() if isinstance(v, dict)},
        "points": [{"id": p.id, "params": p.params, "run_dir": f"runs/{p.id}",
                    "base": str(p.base), "overrides": p.overrides, "n_steps": p.n_steps,
                    "fingerprint": p.fingerprint} for p in sweep.points],
    }
    (out / "sweep.json").write_text(json.dumps(doc, indent=2, default=str))


# --------------------------------------------------------------------------- other machines

def serve(sweep: Sweep, nodes: list[str], connect: list[str], out: Path,
          stream: TextIO, poll_s: float = 1.0) -> int:
    """The other machine's side of a sweep: start ``suscosim node NODE --run <id>`` for each
    point of the sweep as soon as that point's orchestrator answers on the router, until every
    point has been served to the end (or is done in ``out``, when the folder is shared).

    Returns 0 when every point was served (or found done), 130 when interrupted.
    """
    from cosim import keys
    from cosim.bus import ZenohBus, zenoh_config

    ids = {p.id: p for p in sweep.points}
    served_ok: set[str] = set()
    running: dict[str, list[subprocess.Popen]] = {}
    cooldown: dict[str, float] = {}  # a node that failed: wait before serving that id again
    logs = out / "serve"
    logs.mkdir(parents=True, exist_ok=True)
    bus = ZenohBus(zenoh_config(connect, None, mode="client"))  # through a router
    pattern = keys.key("*", keys.ORCHESTRATOR, keys.SCENARIO)
    stream.write(f"suscosim sweep {sweep.name}: serving {', '.join(nodes)} for "
                 f"{len(ids)} points via {', '.join(connect)}\n")
    stream.flush()
    try:
        while True:
            for pid in ids:
                if pid not in served_ok and point_state(ids[pid], out / "runs" / pid,
                                                        sweep.fatigue) == "done":
                    served_ok.add(pid)  # done in a shared sweep folder
            if len(served_ok) == len(ids) and not running:
                return 0
            live: set[str] = set()
            for reply in bus.session.get(pattern, timeout=min(0.5, poll_s)):
                if reply.ok is not None:
                    live.add(keys.parse_key(str(reply.ok.key_expr))[0])
            now = time.monotonic()
            for pid in sorted(live & ids.keys()):
                if pid in served_ok or pid in running or cooldown.get(pid, 0.0) > now:
                    continue
                procs = []
                for n in nodes:
                    cmd = [sys.executable, "-m", "orchestrator", "node", n, "--run", pid]
                    for ep in connect:
                        cmd += ["--connect", ep]
                    procs.append(_start(cmd, logs / f"{pid}.{n}.log"))
                running[pid] = procs
                stream.write(f"  {pid}: started {', '.join(nodes)}\n")
                stream.flush()
            for pid, procs in list(running.items()):
                codes = [pr.poll() for pr in procs]
                if any(c is None for c in codes):
                    continue
                del running[pid]
                if all(c == 0 for c in codes):
                    served_ok.add(pid)
                    stream.write(f"  {pid}: done ({len(served_ok)}/{len(ids)})\n")
                else:
                    cooldown[pid] = time.monotonic() + 10.0
                    stream.write(f"  {pid}: node exit codes {codes} (served again if the "
                                 f"sweep reruns it)\n")
                stream.flush()
            time.sleep(poll_s)
    except KeyboardInterrupt:
        return 130
    finally:
        for procs in running.values():
            for pr in procs:
                _kill_group(pr)
        bus.close()


# --------------------------------------------------------------------------- CLI

def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="suscosim sweep",
                                 description="Run a grid of scenarios, several at once.")
    ap.add_argument("sweep_file", metavar="SWEEP.toml")
    ap.add_argument("--out", help="sweep folder (default sweeps/<name>)")
    ap.add_argument("--jobs", type=int, help="runs at once (default: the file's, else "
                    "cores // 2, at least 1; each run is 4 node processes)")
    ap.add_argument("--connect", action="append", default=[],
                    help="Zenoh router endpoint every run goes through (the same bus for all "
                         "runs; needed for --external)")
    ap.add_argument("--external", action="append", default=[], metavar="NODE",
                    help="do not start NODE: it is started elsewhere (docs/sweeps.md)")
    ap.add_argument("--serve", action="append", default=[], metavar="NODE",
                    help="on another machine: start NODE for every point's run as it "
                         "appears on the router given by --connect (docs/sweeps.md)")
    ap.add_argument("--no-fatigue", action="store_true", help="skip the fatigue worker")
    ap.add_argument("--list", action="store_true",
                    help="validate and list the points (and whether they are done); run nothing")
    return ap


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    if args.jobs is not None and args.jobs < 1:
        print("suscosim sweep: error: --jobs must be >= 1", file=sys.stderr)
        return 2
    if (args.external or args.serve) and not args.connect:
        print("suscosim sweep: error: --external and --serve need --connect (a router "
              "both machines reach)", file=sys.stderr)
        return 2
    try:
        sweep = load_sweep(args.sweep_file, jobs=args.jobs,
                           fatigue=False if args.no_fatigue else None)
        out = Path(args.out) if args.out else Path("sweeps") / sweep.name
        print(f"suscosim sweep {sweep.name}: {len(sweep.points)} points, validating ...",
              flush=True)
        validate_points(sweep, out)
    except SuscosimError as exc:
        print(f"suscosim sweep: error: {exc}", file=sys.stderr)
        return exc.exit_code if exc.exit_code == 2 else 2
    if args.serve:
        from .node_main import NODE_MODULES

        bad = [n for n in args.serve if n not in NODE_MODULES]
        if bad:
            print(f"suscosim sweep: error: --serve {bad[0]}: expected one of "
                  + ", ".join(sorted(NODE_MODULES)), file=sys.stderr)
            return 2
        return serve(sweep, args.serve, args.connect, out, sys.stdout)
    out.mkdir(parents=True, exist_ok=True)
    states = {p.id: point_state(p, out / "runs" / p.id, sweep.fatigue) for p in sweep.points}
    if args.list:
        for p in sweep.points:
            print(f"  {p.id:<{MAX_ID}} {states[p.id]:<8} {p.n_steps:>8} steps  "
                  f"{_params_text(p.params)}")
        return 0
    write_sweep_json(sweep, out)
    todo = [(p, states[p.id]) for p in sweep.points if states[p.id] != "done"]
    n_done = len(sweep.points) - len(todo)
    print(f"  -> {out}: {len(todo)} to run ({n_done} already done), {sweep.jobs} at once"
          + (", fatigue on" if sweep.fatigue else ""), flush=True)
    runner = Runner(sweep, out, args.connect, args.external, sys.stderr)
    t0 = time.monotonic()
    completed = runner.execute(todo) if todo else True
    rows = result_rows(sweep, out, runner.status)
    write_results(out, rows)
    print(results_table(sweep, rows))
    n_failed = sum(r["status"] != "ok" for r in rows)
    print(f"sweep {sweep.name}: {len(rows) - n_failed} ok, {n_failed} failed, "
          f"{time.monotonic() - t0:.0f} s; results in {out / 'results.csv'}")
    if not completed:
        print("suscosim sweep: interrupted (rerun the same command to resume)", file=sys.stderr)
        return 130
    return 1 if n_failed else 0


if __name__ == "__main__":
    sys.exit(main())
