"""Memory and disk of long runs (#32): peak RSS per process, journal and table bytes per coupled
step, and the commands that read a finished run folder.

    python -m bench memory [--steps 10000 100000 1000000] [--corner-steps 100000] [--keep DIR]
                           [--report]
    python -m bench memory --post RUN_DIR ... [--scope-s 120] [--only CMD ...]
    python -m bench tile-table RUN_DIR OUT_DIR TIMES

``memory``: the Chapter 3 lumped quarter car (distributed, h = 1 ms: ``run.t_end`` = steps x
h) at each ``--steps`` and the Chapter 6 realistic corner with live fatigue (h = 0.5 ms, the
road made long enough for ``--corner-steps``: 4235 steps per 20 m) once: wall time, peak RSS
of each process (VmHWM as last sampled every 0.1 s), bytes per step of the journal (its bar:
1.5x the 8-byte ``values`` a step carries, the table's columns less ``k`` and ``t``), CSV and
Parquet, then ``suscosim export`` of the journal (time, peak RSS) and whether the table it
rebuilds equals the recorder's ``table.parquet`` bit for bit; ``--report`` also times
``suscosim report``. ``--post``: on finished run folders (those ``--keep`` kept, or longer ones
made by ``tile-table``), the wall time and peak RSS of every command that reads one:
``report``, batch ``fatigue``, ``export``, ``replay``, ``scope``. Markdown table on stdout;
docs/memory.md holds the measured one.

``tile-table``: a longer run folder from a shorter one: ``table.parquet`` repeated TIMES times
end to end (time shifted by the run's duration each repeat, ``k`` renumbered) in row groups as
the recorder writes them; the scenario and summary copied (``rows``, ``run.t_end`` and
``road.length_m`` scaled). For the post-processing commands at 10^6 rows without a 10^6-step
run; the loads repeat, so it is a memory and time probe, not a result. Prints the rows written.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
CH3 = ROOT / "scenarios" / "ch3_step_quarter_car.toml"
CH6 = ROOT / "scenarios" / "thesis" / "ch6_realistic_qvm.toml"
CH6_STEPS_PER_M = 4235 / 20.0
POST = ("run", "export", "report", "fatigue", "replay", "scope")
"""The suscosim commands whose processes are sampled (``run``: the orchestrator)."""


def _children(pid: int) -> list[int]:
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        try:
            kids = [int(x) for x in Path(f"/proc/{p}/task/{p}/children").read_text().split()]
        except OSError:
            kids = []
        out += kids
        todo += kids
    return out


def _sample(pid: int) -> tuple[str, int] | None:
    """(process name, VmHWM bytes) of a live suscosim process."""
    try:
        args = [a.decode(errors="replace")
                for a in Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0") if a]
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return None
    if "orchestrator.export" in args:
        name = "export"
    elif "node" in args:
        name = args[args.index("node") + 1]
    elif any(a in POST for a in args):
        name = next(a for a in args if a in POST)
        name = "orchestrator" if name == "run" else name
    else:
        return None
    hwm = next((int(line.split()[1]) * 1024 for line in status.splitlines()
                if line.startswith("VmHWM:")), 0)
    return name, hwm


def measured(cmd: list[str]) -> tuple[float, dict[str, int], str]:
    """Run ``cmd``; (wall s, peak RSS by process name, stderr tail)."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            env=dict(os.environ, PYTHONPATH=str(ROOT)))
    peak: dict[int, tuple[str, int]] = {}
    while proc.poll() is None:
        for pid in [proc.pid, *_children(proc.pid)]:
            s = _sample(pid)
            if s is not None:
                peak[pid] = s
        time.sleep(0.1)
    wall = time.perf_counter() - t0
    err = proc.stderr.read().decode(errors="replace") if proc.stderr else ""
    by_name: dict[str, int] = {}
    for name, hwm in peak.values():
        by_name[name] = max(by_name.get(name, 0), hwm)
    if proc.returncode:
        raise RuntimeError(f"{' '.join(cmd[2:5])}: exit {proc.returncode}: {err[-600:]}")
    return wall, by_name, err[-600:]


def same_table(a: Path, b: Path) -> str:
    """'bytes' when the two Parquet files are identical, 'values' when every column is equal
    bit for bit (read in batches), else what differs."""
    if a.read_bytes() == b.read_bytes():
        return "bytes"
    import pyarrow.parquet as pq

    fa, fb = pq.ParquetFile(a), pq.ParquetFile(b)
    if fa.schema_arrow != fb.schema_arrow or fa.metadata.num_rows != fb.metadata.num_rows:
        return "schema or rows differ"
    for ba, bb in zip(fa.iter_batches(65536), fb.iter_batches(65536), strict=True):
        if not ba.equals(bb):
            return "values differ"
    return "values"


def case(label: str, scenario: Path, sets: list[str], work: Path, report: bool) -> dict:
    out = work / label
    shutil.rmtree(out, ignore_errors=True)
    cmd = [sys.executable, "-m", "orchestrator", "run", str(scenario), "--out", str(out),
           "--quiet", "--set", f'run.id="mem-{label}"']
    for s in sets:
        cmd += ["--set", s]
    wall, rss, _err = measured(cmd)
    summary = json.loads((out / "summary.json").read_text())
    steps = int(summary["rows"])
    import pyarrow.parquet as pq

    values = len(pq.ParquetFile(out / "table.parquet").schema_arrow.names) - 2
    size = {n: (out / n).stat().st_size for n in ("journal.msgpack", "table.csv",
                                                   "table.parquet")}
    rebuilt = work / f"{label}-export"
    shutil.rmtree(rebuilt, ignore_errors=True)
    ex_wall, ex_rss, _ = measured([sys.executable, "-m", "orchestrator.export",
                                   str(out / "journal.msgpack"), "--out", str(rebuilt)])
    row = {"case": label, "steps": steps, "values": values, "wall_s": wall,
           "steps_per_s": summary.get("steps_per_s"), "rss_mb": {n: v / 2**20
                                                                  for n, v in rss.items()},
           "journal_B_per_step": size["journal.msgpack"] / steps,
           "journal_x_values": size["journal.msgpack"] / steps / (8 * values),
           "csv_B_per_step": size["table.csv"] / steps,
           "parquet_B_per_step": size["table.parquet"] / steps,
           "export_s": ex_wall, "export_rss_mb": ex_rss.get("export", 0) / 2**20,
           "parquet_equals_rebuilt": same_table(out / "table.parquet",
                                                rebuilt / "table.parquet")}
    if report:
        r_wall, r_rss, _ = measured([sys.executable, "-m", "orchestrator", "report", str(out),
                                     "--out", str(work / f"{label}.html")])
        row["report_s"], row["report_rss_mb"] = r_wall, r_rss.get("report", 0) / 2**20
    shutil.rmtree(rebuilt, ignore_errors=True)
    return row


def post(label: str, run: Path, work: Path, scope_s: float,
         only: list[str] | None = None, fatigue_sets: list[str] | None = None) -> dict:
    """Peak RSS [MB] and wall time [s] of the commands that read a finished run folder:
    ``report``, batch ``fatigue`` (a run with ``plant/arm`` loads), ``export RUN --format
    parquet`` (batches of the table), ``replay --fast`` (the journal republished, nobody
    listening), ``scope --fast`` (the journal replayed into the page's state, at most
    ``scope_s`` s)."""
    import pyarrow.parquet as pq

    py = sys.executable
    names = pq.ParquetFile(run / "table.parquet").schema_arrow.names
    cmds = {"report": [py, "-m", "orchestrator", "report", str(run), "--out",
                       str(work / f"{label}.html")],
            "export": [py, "-m", "orchestrator", "export", str(run), "--format", "parquet",
                       "--out", str(work / f"{label}-export-parquet")]}
    if any(n.startswith("plant/arm/") for n in names):
        cmds["fatigue"] = [py, "-m", "orchestrator", "fatigue", str(run), "--quiet", "--out",
                           str(work / f"{label}-fatigue")]
    if (run / "journal.msgpack").is_file():
        cmds["replay"] = [py, "-m", "orchestrator", "replay", str(run), "--fast", "--wait",
                          "0", "--listen", "tcp/127.0.0.1:0"]
        cmds["scope"] = [py, "-m", "orchestrator", "scope", str(run), "--replay", "--fast",
                         "--port", "0", "--duration", f"{scope_s:g}"]
    if "fatigue" in cmds:
        for item in fatigue_sets or []:
            cmds["fatigue"] += ["--set", item]
    out: dict = {"case": label, "rows": pq.ParquetFile(run / "table.parquet").metadata.num_rows}
    for name, cmd in cmds.items():
        if only and name not in only:
            continue
        try:
            wall, rss, _ = measured(cmd)
            out[name] = (wall, rss.get(name, 0) / 2**20)
        except RuntimeError as exc:
            out[name] = (float("nan"), float("nan"))
            print(f"# {label} {name}: {exc}", file=sys.stderr)
        print(f"# {label} {name}: {out[name]}", file=sys.stderr, flush=True)
    for d in ("export-parquet", "fatigue"):
        shutil.rmtree(work / f"{label}-{d}", ignore_errors=True)
    return out


def post_table(rows: list[dict]) -> str:
    names = ["report", "fatigue", "export", "replay", "scope"]
    head = ["case", "rows", *[f"{n} s (MB)" for n in names]]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        cells = [r["case"], str(r["rows"])]
        for n in names:
            cells.append(f"{r[n][0]:.0f} ({r[n][1]:.0f})" if n in r else "-")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def table(rows: list[dict]) -> str:
    names = sorted({n for r in rows for n in r["rss_mb"]})
    head = ["case", "steps", "wall s", "steps/s", *[f"{n} MB" for n in names],
            "journal B/step (x values)", "csv B/step", "parquet B/step", "export s (MB)",
            "parquet = rebuilt"]
    if any("report_s" in r for r in rows):
        head.append("report s (MB)")
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        cells = [r["case"], str(r["steps"]), f"{r['wall_s']:.0f}", f"{r['steps_per_s']:.0f}",
                 *[f"{r['rss_mb'].get(n, 0):.0f}" if n in r["rss_mb"] else "-" for n in names],
                 f"{r['journal_B_per_step']:.0f} ({r['journal_x_values']:.2f}x)",
                 f"{r['csv_B_per_step']:.0f}", f"{r['parquet_B_per_step']:.0f}",
                 f"{r['export_s']:.0f} ({r['export_rss_mb']:.0f})",
                 r["parquet_equals_rebuilt"]]
        if "report_s" in r:
            cells.append(f"{r['report_s']:.0f} ({r['report_rss_mb']:.0f})")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def memory(args: argparse.Namespace) -> int:
    """``memory``: long runs' memory and disk, or (``--post``) the commands reading a run."""
    if args.post is not None:
        work = Path(tempfile.mkdtemp(prefix="bench_memory-post-"))
        rows = [post(Path(d).name, Path(d), work, args.scope_s, args.only, args.fatigue_set)
                for d in args.post]
        print(post_table(rows))
        shutil.rmtree(work, ignore_errors=True)
        return 0
    work = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="bench_memory-"))
    work.mkdir(parents=True, exist_ok=True)
    rows = []
    print(f"# load average at the start: {os.getloadavg()[0]:.1f}", file=sys.stderr)
    for n in args.steps:
        rows.append(case(f"ch3-{n}", CH3, [f"run.t_end={n * 1e-3:g}",
                                           "run.stall_timeout_s=120"], work, args.report))
        print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
    if args.corner_steps:
        length = args.corner_steps / CH6_STEPS_PER_M
        rows.append(case(f"ch6-fatigue-{args.corner_steps}", CH6,
                         [f"road.length_m={length:.3f}", "run.stall_timeout_s=120"], work,
                         args.report))
        print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
    print(f"# load average at the end: {os.getloadavg()[0]:.1f}", file=sys.stderr)
    print(table(rows))
    if not args.keep:
        shutil.rmtree(work, ignore_errors=True)
    return 0


# ---- tile-table -----------------------------------------------------------------------------
def tile(src: Path, out: Path, times: int) -> int:
    """Write ``out`` (a run folder); the rows written."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    out.mkdir(parents=True, exist_ok=True)
    f = pq.ParquetFile(src / "table.parquet")
    rg = f.metadata.row_group(0)
    comp = rg.column(0).compression.lower()
    t_all = f.read(columns=["t"]).column(0).to_numpy()
    n = t_all.size
    span = float(t_all[-1] - t_all[0] + (t_all[1] - t_all[0]))
    w = pq.ParquetWriter(out / "table.parquet", f.schema_arrow, compression=comp)
    for r in range(times):
        for i in range(f.metadata.num_row_groups):
            b = f.read_row_group(i)
            cols = []
            for name, col in zip(b.column_names, b.columns, strict=True):
                a = col.to_numpy()
                if name == "t":
                    a = a + r * span
                elif name == "k":
                    a = a + r * n
                cols.append(pa.array(a, type=col.type))
            w.write_table(pa.Table.from_arrays(cols, schema=f.schema_arrow))
    w.close()
    for name in ("scenario.json", "summary.json"):
        if (src / name).is_file():
            d = json.loads((src / name).read_text())
            if name == "summary.json":
                d["rows"] = n * times
            else:
                run, road = d.get("run", {}), d.get("road", {})
                if "t_end" in run:
                    run["t_end"] = float(np.float64(run["t_end"]) * times)
                if "length_m" in road:
                    road["length_m"] = float(road["length_m"]) * times
            (out / name).write_text(json.dumps(d, indent=1))
    for extra in ("fatigue",):
        if (src / extra).is_dir() and not (out / extra).exists():
            shutil.copytree(src / extra, out / extra)
    return n * times


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="command", required=True)
    p = sub.add_parser("memory", help="peak RSS, bytes per step, export of long runs")
    p.add_argument("--steps", type=int, nargs="*", default=[10_000, 100_000, 1_000_000],
                   help="coupled steps of the lumped quarter car runs")
    p.add_argument("--corner-steps", type=int, default=100_000,
                   help="coupled steps of the realistic corner with live fatigue (0: none)")
    p.add_argument("--keep", help="keep the run folders here (default: a temporary folder)")
    p.add_argument("--report", action="store_true", help="also time suscosim report")
    p.add_argument("--post", nargs="*", default=None, metavar="RUN_DIR",
                   help="measure only the commands that read these finished run folders "
                        "(report, fatigue, export, replay, scope: `post`), no runs")
    p.add_argument("--scope-s", type=float, default=120.0,
                   help="longest scope replay measured [s] (--post)")
    p.add_argument("--only", nargs="*", help="--post: only these commands")
    p.add_argument("--fatigue-set", action="append", default=[], metavar="KEY=VALUE",
                   help="--post: a --set of the batch fatigue measured (e.g. a coarser "
                        "mesh, to measure 10^6 rows in minutes)")
    p.set_defaults(fn=memory)
    p = sub.add_parser("tile-table", help="a longer run folder from a shorter one")
    p.add_argument("run_dir", type=Path)
    p.add_argument("out_dir", type=Path)
    p.add_argument("times", type=int)
    p.set_defaults(fn=lambda a: print(tile(a.run_dir, a.out_dir, a.times)))
    args = ap.parse_args(argv)
    return int(args.fn(args) or 0)


if __name__ == "__main__":
    raise SystemExit(main())
