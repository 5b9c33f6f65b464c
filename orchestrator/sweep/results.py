"""A sweep's results (a row per point from the run folders, results.csv/.json, sweep.json) and
its one progress display on stderr."""

from __future__ import annotations

import csv
import json
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Protocol, TextIO

from cosim.run_folder import read_json, replaced

from .phases import point_state
from .spec import FATIGUE_COLUMNS, Point, Sweep


def _fmt(v: Any) -> str:
    if v is None or v == "":
        return ""
    return f"{v:.4g}" if isinstance(v, float) else str(v)


def result_rows(sweep: Sweep, out: Path, status: dict[str, tuple[str, str]]) -> list[dict]:
    rows = []
    for p in sweep.points:
        d = sweep.run_dir(out, p)
        summary = read_json(d / "summary.json")
        summary = summary if isinstance(summary, dict) else {}
        fat = read_json(d / "fatigue" / "summary.json") if sweep.fatigue else None
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
            row.update(zip(FATIGUE_COLUMNS, (fat.get(k) for k in (
                "min_life_repeats", "min_life_km", "max_damage_per_pass", "critical_node_id")),
                strict=True))
        if sweep.design is not None:
            row.update(ride_columns(d) if st == "ok" else {})
        if sweep.fork is not None:  # [sweep] fork_at: its law acts from fork_at on
            row["fork_at"] = sweep.fork.at
            row["parent"] = sweep.fork.parent_of[p.id].id
        meta = read_json(d / "point.json")
        worker = meta.get("worker") if isinstance(meta, dict) else None
        row["worker"] = _worker_text(worker) if isinstance(worker, dict) else None
        row["run_dir"] = sweep.run_dir_text(p)
        rows.append(row)
    return rows


RIDE_KEYS = ("a_b_rms", "a_b_wk_rms", "a_w_rms", "sws", "defl_rms", "dtl_rms", "f_d_rms")
"""The ride metrics (:func:`nodes.recorder.ride_metrics.metric_values`) a design's results carry
as ``ride <key>`` (per corner ``ride a_b[2]_rms``)."""


def ride_columns(run_dir: Path) -> dict[str, float]:
    table_path = run_dir / "table.parquet"
    if not table_path.is_file():
        return {}
    from cosim.table import read_table
    from nodes.recorder.ride_metrics import metric_values

    try:
        values = metric_values(read_table(table_path))
    except (OSError, ValueError, KeyError):
        return {}
    return {f"ride {k}": float(v) for k, (v, _u, _l) in values.items()
            if k.split("[")[0] + ("" if "[" not in k else k[k.index("]") + 1:]) in RIDE_KEYS}


def _worker_text(w: dict[str, Any]) -> str:
    if w.get("executor") == "dask":
        return str(w.get("name") or w.get("address"))
    return str(w.get("host", ""))


def write_results(out: Path, rows: list[dict]) -> None:
    columns = [c for c in dict.fromkeys(c for r in rows for c in r)  # not a channel no run has
               if not c.endswith((" peak", " rms")) or any(r.get(c) is not None for r in rows)]
    rows = [{c: r.get(c) for c in columns} for r in rows]
    with replaced(out / "results.csv", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=columns)
        w.writeheader()
        for r in rows:
            w.writerow({c: "" if r.get(c) is None else r.get(c) for c in columns})
    with replaced(out / "results.json") as fh:
        fh.write(json.dumps(rows, indent=2, default=str))


def results_table(sweep: Sweep, rows: list[dict]) -> str:
    cols = ["point", *(a.name for a in sweep.axes), "status", "wall_s", "steps_per_s"]
    metrics = [c for c in (rows[0] if rows else {}) if c.endswith((" peak", " rms"))]
    extra = [c for c in metrics if any(r.get(c) is not None for r in rows)][:3]
    cols += extra
    if sweep.fatigue:
        cols += ["life_km", "life_repeats", "critical_node"]
    if sweep.fork is not None:
        cols.append("parent")
    if len({r.get("worker") for r in rows} - {None}) > 1:  # points ran on several workers
        cols.append("worker")
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
        "set": sweep.fixed, "fatigue": sweep.fatigue, "sweep_file": str(sweep.path.resolve()),
        "variants": {k: v for k, v in sweep.raw_grid.items() if isinstance(v, dict)},
        "points": [{"id": p.id, "params": p.params, "run_dir": sweep.run_dir_text(p),
                    "base": str(p.base), "overrides": p.overrides, "n_steps": p.n_steps,
                    "fingerprint": p.fingerprint} for p in sweep.points],
    }
    if sweep.fork is not None:
        from .fork import SEMANTICS

        plan = sweep.fork
        doc["fork"] = {"fork_at": plan.at, "semantics": SEMANTICS, "report": "fork.json",
                       "parents": [{"id": pa.id, "run_dir": f"parents/{pa.id}",
                                    "controller": pa.law, "k": pa.k, "t": pa.t,
                                    "n_steps": pa.point.n_steps, "base": str(pa.point.base),
                                    "overrides": pa.point.overrides,
                                    "fingerprint": pa.point.fingerprint,
                                    "points": [p.id for p in pa.members]} for pa in plan.parents]}
    if sweep.design is not None:
        d = sweep.design
        doc["design"] = {"method": d.method, "n": d.n, "seed": d.seed, "parameters": d.keys,
                         "ranges": [{"key": r.key, "low": r.low, "high": r.high,
                                     "scale": r.scale} for r in d.ranges],
                         "sensitivity": "sensitivity.json"}
    with replaced(out / "sweep.json") as fh:
        fh.write(json.dumps(doc, indent=2, default=str))


class Job(Protocol):
    point: Point
    phase: str
    t0: float
    fresh: bool

    def step(self) -> int | None:
        ...


class Display:
    """A line per running point, redrawn on a terminal; on a pipe, events and a status."""

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

    def update(self, jobs: Sequence[Job], done: int, failed: int, pending: int,
               steps_done: int) -> None:
        elapsed = time.monotonic() - self.t0
        if not self.tty and time.monotonic() - self.last_status < 30.0:
            return
        steps = steps_done + sum((j.step() or 0) if j.phase == "run" else j.point.n_steps
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

    def _frac(self, j: Job) -> str:
        if j.phase != "run":
            return j.phase
        k = j.step()
        return "starting" if k is None else f"{100 * k / max(1, j.point.n_steps):.0f}%"

    def _bar(self, j: Job) -> str:
        t = time.monotonic() - j.t0
        if j.phase != "run":
            return f"{j.phase:<8} {t:6.0f} s"
        k = j.step()
        if k is None:
            return f"starting {t:6.0f} s"
        n = max(1, j.point.n_steps)
        frac = min(1.0, max(0.0, k / n))
        fill = int(frac * 24)
        return (f"run [{'#' * fill}{'.' * (24 - fill)}] {100 * frac:5.1f}% step {k}/{n} {t:6.0f} s")

    def close(self) -> None:
        self._clear()


def event_line(run_dir: Path, pid: str, status: str, err: str, i: int, n: int) -> str:
    head = f"[{i}/{n}] {status:<6} {pid}"
    if status != "ok":
        return f"{head}: {err}"
    s = read_json(run_dir / "summary.json") or {}
    text = f"{head}  wall {s.get('wall_s', 0):.1f} s, {s.get('steps_per_s', 0):.0f} steps/s"
    f = read_json(run_dir / "fatigue" / "summary.json")
    if isinstance(f, dict):
        text += f", min life {_fmt(f.get('min_life_km'))} km"
    return text
