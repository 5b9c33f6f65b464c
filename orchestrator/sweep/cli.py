"""The command line of ``suscosim sweep``."""

from __future__ import annotations

import argparse
import os
import sys
import time
from functools import partial
from pathlib import Path

from cosim.errors import SuscosimError
from cosim.run_folder import write_json
from cosim.zenoh_options import add_connect_argument

from ..cli_util import fail, parse_args
from .dask_exec import DaskRunner
from .fork import fork_header, fork_report, fork_text, parent_state
from .local import Runner
from .phases import point_state
from .results import result_rows, results_table, write_results, write_sweep_json
from .sensitivity import sensitivity, sensitivity_table, write_sensitivity
from .serve import serve
from .spec import MAX_ID, MAX_POINTS, _params_text, load_sweep, validate_points

_fail = partial(fail, "suscosim sweep")


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="suscosim sweep",
                                 description="Run a grid of scenarios, several at once.")
    ap.add_argument("sweep_file", metavar="SWEEP.toml")
    ap.add_argument("--out", help="sweep folder (default sweeps/<name>)")
    ap.add_argument("--jobs", type=int, help="runs at once (default: the file's, else "
                    "cores // 2, at least 1; each run is 4 node processes)")
    add_connect_argument(ap, "Zenoh router endpoint every run goes through (the same bus for "
                             "all runs; needed for --external)", metavar=None, default=[])
    ap.add_argument("--external", action="append", default=[], metavar="NODE",
                    help="do not start NODE: it is started elsewhere (docs/sweeps.md)")
    ap.add_argument("--serve", action="append", default=[], metavar="NODE",
                    help="on another machine: start NODE for every point's run as it "
                         "appears on the router given by --connect (docs/sweeps.md)")
    ap.add_argument("--executor", choices=("local", "dask"), default="local",
                    help="local: runs as subprocesses here, --jobs at once (default); dask: "
                         "each point whole on a worker of the Dask cluster at --scheduler")
    ap.add_argument("--scheduler", metavar="ADDRESS",
                    help="the Dask scheduler, e.g. tcp://HOST:8786 (suscosim cluster)")
    ap.add_argument("--no-fatigue", action="store_true", help="skip the fatigue worker")
    ap.add_argument("--runs-dir", metavar="DIR",
                    help="the run folders' folder, e.g. one the Dask workers share (default: "
                         "OUT/runs; without --out the sweep file's runs_dir)")
    ap.add_argument("--max-points", type=int, default=MAX_POINTS, metavar="N",
                    help=f"run a sweep of more than {MAX_POINTS} points (default: refused)")
    ap.add_argument("--list", action="store_true",
                    help="validate and list the points (and whether they are done); run nothing")
    return ap


def main(argv: list[str] | None = None) -> int:
    args = parse_args(build_parser(), argv)
    if isinstance(args, int):
        return args
    if args.jobs is not None and args.jobs < 1:
        return _fail("--jobs must be >= 1")
    if args.executor == "dask" and not args.scheduler:
        return _fail("--executor dask needs --scheduler tcp://HOST:8786 (start one with "
                     "'suscosim cluster')")
    if args.executor == "dask" and (args.external or args.serve or args.connect):
        return _fail("--executor dask runs every point whole on one worker; --connect, "
                     "--external and --serve are for the local executor")
    if args.scheduler and args.executor != "dask":
        return _fail("--scheduler needs --executor dask")
    if (args.external or args.serve) and not args.connect:
        return _fail("--external and --serve need --connect (a router both machines reach)")
    try:
        sweep = load_sweep(args.sweep_file, jobs=args.jobs,
                           fatigue=False if args.no_fatigue else None, max_points=args.max_points)
        out = Path(args.out) if args.out else Path("sweeps") / sweep.name
        if args.runs_dir:  # the command line's shared folder for the run folders
            sweep.runs_dir = Path(args.runs_dir).resolve()
        elif args.out and sweep.runs_dir is not None:  # --out wins over the file (#46)
            print(f"suscosim sweep: runs under {out / 'runs'} (--out), not the sweep file's "
                  f"runs_dir {sweep.runs_dir} (--runs-dir DIR to keep a shared one)", flush=True)
            sweep.runs_dir = None
        print(f"suscosim sweep {sweep.name}: {len(sweep.points)} points, validating ...",
              flush=True)
        validate_points(sweep, out)
    except SuscosimError as exc:
        return _fail(str(exc))
    if sweep.fork is not None and (args.executor == "dask" or args.serve or args.external):
        return _fail("[sweep] fork_at works with the local executor only, without --external "
                     "and --serve (a fork needs its parent's run folder and checkpoint where "
                     "its nodes run)")
    keyed = os.environ.get("SUSCOSIM_KEY") or os.environ.get("SUSCOSIM_KEY_FILE")
    if args.serve:
        from ..node_main import NODE_MODULES

        bad = [n for n in args.serve if n not in NODE_MODULES]
        if bad:
            return _fail(f"--serve {bad[0]}: expected one of " + ", ".join(sorted(NODE_MODULES)))
        if not keyed:
            return _fail("--serve needs the sweep's secret: set SUSCOSIM_KEY (or "
                         "SUSCOSIM_KEY_FILE) to the same secret here and on the machine that "
                         "runs the sweep (the messages of a run are signed; docs/reliability.md)")
        return serve(sweep, args.serve, args.connect, out, sys.stdout)
    if args.external and not keyed:
        print("suscosim sweep: warning: --external without SUSCOSIM_KEY / SUSCOSIM_KEY_FILE: "
              "each run draws its own secret (RUN/run.key), which 'suscosim sweep --serve' on "
              "another machine cannot know; set the same SUSCOSIM_KEY on both sides",
              file=sys.stderr)
    out.mkdir(parents=True, exist_ok=True)
    states = {p.id: point_state(p, sweep.run_dir(out, p), sweep.fatigue) for p in sweep.points}
    if sweep.fork is not None:
        print(fork_header(sweep.fork), flush=True)
    if args.list:
        if sweep.fork is not None:
            for pa in sweep.fork.parents:
                state = parent_state(pa, sweep.fork.parent_dir(out, pa))
                print(f"  {pa.id:<{MAX_ID}} {state:<8} {pa.point.n_steps:>8} steps  parent "
                      f"({pa.law}) of {len(pa.members)} point(s), checkpoint k = {pa.k}")
        for p in sweep.points:
            fork = (f"  (fork of {sweep.fork.parent_of[p.id].id})"
                    if sweep.fork is not None else "")
            print(f"  {p.id:<{MAX_ID}} {states[p.id]:<8} {p.n_steps:>8} steps  "
                  f"{_params_text(p.params)}{fork}")
        return 0
    write_sweep_json(sweep, out)
    todo = [(p, states[p.id]) for p in sweep.points if states[p.id] != "done"]
    runner: Runner | DaskRunner
    if args.executor == "dask":
        try:
            runner = DaskRunner(sweep, out, args.scheduler, sys.stderr)
        except SuscosimError as exc:
            return _fail(str(exc))
        where = runner.workers_text()
    else:
        runner = Runner(sweep, out, args.connect, args.external, sys.stderr)
        where = f"{sweep.jobs} at once"
    print(f"  -> {out}: {len(todo)} to run ({len(sweep.points) - len(todo)} already done), {where}"
          + (", fatigue on" if sweep.fatigue else ""), flush=True)
    t0 = time.monotonic()
    if todo:
        completed = runner.execute(todo)
    else:
        completed = True
        if isinstance(runner, DaskRunner):
            runner.client.close()
    rows = result_rows(sweep, out, runner.status)
    write_results(out, rows)
    print(results_table(sweep, rows))
    if sweep.design is not None:
        sens = sensitivity(sweep, rows)
        write_sensitivity(out, sens)
        print(sensitivity_table(sens))
    if sweep.fork is not None:
        doc = fork_report(sweep, sweep.fork, out)
        doc["elapsed_s"] = time.monotonic() - t0  # this session's, the parents' wait included
        write_json(doc, out / "fork.json")
        print(fork_text(doc) + f"\n  in {out / 'fork.json'}")
    n_failed = sum(r["status"] != "ok" for r in rows)
    print(f"sweep {sweep.name}: {len(rows) - n_failed} ok, {n_failed} failed, "
          f"{time.monotonic() - t0:.0f} s; results in {out / 'results.csv'}")
    if not completed:
        print("suscosim sweep: interrupted (rerun the same command to resume)", file=sys.stderr)
        return 130
    return 1 if n_failed else 0
