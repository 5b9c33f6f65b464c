"""``suscosim COMMAND``: the command line (``run`` and ``check`` here, the other commands in
their modules: :data:`COMMANDS`). Exit codes: 0 success, 1 the run failed (dead node, stall,
abort), 2 bad input (scenario, file, arguments). Every error line starts ``suscosim: error: ``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from cosim import scenario as sc
from cosim import zenoh_options as zo
from cosim.errors import SuscosimError

from .cli_util import ArgumentParser, error_line, interrupt_on_sigterm, num
from .placement import PIN_MODES


def _print_summary(summary: dict) -> None:
    print(f"run {summary['run_id']}: {summary['status']}  mode={summary['mode']} "
          f"exchange={summary['exchange']} coupling={summary['coupling']} h={summary['h']} s "
          f"steps={summary['n_steps']}")
    print(f"  wall {summary['wall_s']:.2f} s, {summary['steps_per_s']:.0f} coupled steps/s")
    if summary.get("cores"):
        print("  cores: " + ", ".join(f"{n} {c}" for n, c in summary["cores"].items())
              + (f" (in the background, SCHED_IDLE: {', '.join(summary['background'])})"
                 if summary.get("background") else ""))
    if summary.get("sinks"):  # buffered, never waited for: how far behind they fell
        print("  sinks (buffered): " + ", ".join(
            f"{n} lagged <= {v['max_lag_steps']} steps, {v['drain_s']:.2f} s after the chain"
            for n, v in summary["sinks"].items())
            + (f"; the chain waited {summary['sink_window_held_s']:.2f} s for them "
               "(run.sink_window_s)" if summary.get("sink_window_held_s") else ""))
    if summary.get("inprocess"):
        print(f"  in-process: the sinks took {summary['inprocess']['sink_s']:.2f} s of the "
              f"steps; the chain alone {summary['inprocess']['chain_steps_per_s']:.0f} "
              "steps/s")
    chans = summary.get("channels", {})
    if chans:
        from cosim.formats import si_unit  # the units of the channel schema

        print(f"  {'channel':<34} {'peak':>12} {'rms':>12}  unit")
        for name, st in chans.items():
            print(f"  {name:<34} {st['peak']:>12.5g} {st['rms']:>12.5g}  "
                  f"{si_unit(name) or '-'}")
    res = summary.get("coupling_energy_residual")
    if res:
        from cosim.coupling_energy import WARNING_THRESHOLD

        bonds = ", ".join(f"{b} {100 * v:.3g} %" for b, v in res.items() if b != "total")
        print(f"  coupling energy residual {100 * res['total']:.3g} % ({bonds})")
        if res["total"] > WARNING_THRESHOLD:
            print(f"  warning: the coupling residual is above {100 * WARNING_THRESHOLD:g} % "
                  "(about 1 % peak error, docs/coupling_residual.md): a smaller run.h or "
                  "the jacobian coupling would be more accurate")
    fat = summary.get("fatigue")
    if fat:
        print(f"  fatigue (live): lower-arm min life {num(fat['min_life_km'])} km = "
              f"{num(fat['min_life_repeats'])} repeats, critical node "
              f"{fat['critical_node_id']}  ({fat['files']})")


def cmd_run(args: argparse.Namespace) -> int:
    from .runner import run_scenario

    # SIGTERM (docker compose down, a sweep stopping a run, kill) ends the run like Ctrl-C:
    # the nodes are told to abort and summary.json says "failed: interrupted"
    interrupt_on_sigterm()

    if not (args.scenario or args.resume or args.fork):
        from cosim.errors import ScenarioError

        raise ScenarioError("scenario", None, "a scenario TOML file (or --resume RUN_DIR, "
                            "--fork RUN_DIR@T)")
    scenario = _continued(args) if args.resume or args.fork else _resolved(args)
    print(f"suscosim: run {scenario['run']['id']} -> {scenario['run']['dir']}", flush=True)
    summary = run_scenario(scenario, connect=args.connect, external=args.external,
                           quiet=args.quiet, zenoh_config_file=args.zenoh_config,
                           listen=args.listen, lowlatency=args.lowlatency, pin_mode=args.pin)
    _print_summary(summary)
    print(f"  summary: {Path(scenario['run']['dir']) / 'summary.json'}")
    return 0


def _continued(args: argparse.Namespace) -> dict:
    """The scenario of ``run --resume RUN_DIR`` or ``--fork RUN_DIR@T`` (:mod:`.resume`)."""
    from cosim.errors import ScenarioError

    from . import resume as rs
    from .runner import resolve

    if args.resume and args.fork:
        raise ScenarioError("--resume", args.resume, "either --resume or --fork, not both")
    if args.scenario:
        raise ScenarioError("scenario", args.scenario, "no scenario file with --resume or "
                            "--fork: the run folder's scenario.json is the scenario")
    if args.resume:
        if args.set or args.mode or args.out or args.inprocess:
            raise ScenarioError("--set" if args.set else "--mode" if args.mode else "--out",
                                args.set or args.mode or args.out,
                                "nothing with --resume (it runs the same scenario in the "
                                "same folder; --fork RUN_DIR@T --set ... changes settings)")
        scenario, ck = rs.resume_scenario(args.resume)
        print(f"suscosim: resuming {args.resume} from its checkpoint at step {ck.k} "
              f"(t = {ck.t:g} s)", flush=True)
        return scenario
    overrides = list(args.set or []) + _mode_overrides(args)
    scenario, ck, changed = rs.fork_scenario(args.fork, overrides,
                                             getattr(args, "out", None), resolve)
    fresh = scenario["run"]["resume"]["fresh"]
    print(f"suscosim: fork of {args.fork} at step {ck.k} (t = {ck.t:g} s); changed: "
          f"{', '.join(changed) or 'nothing'}"
          + (f"; starting afresh: {', '.join(fresh)}" if fresh else ""), flush=True)
    return scenario


def _resolved(args: argparse.Namespace) -> dict:
    """The scenario of ``run`` / ``check``: read, ``--set`` applied, resolved (preflight)."""
    from cosim.errors import ScenarioError

    from .runner import resolve

    overrides = list(args.set or []) + _mode_overrides(args)
    try:
        return resolve(sc.load(args.scenario, overrides), getattr(args, "out", None))
    except ScenarioError as exc:
        raise sc.override_hint(exc, overrides) from None


def cmd_check(args: argparse.Namespace) -> int:
    """Resolve a scenario as ``run`` does, start nothing; print it (TOML, or ``--json``)."""
    scenario = _resolved(args)
    run = scenario["run"]
    if args.json:
        print(json.dumps(scenario, indent=2, sort_keys=True))
        return 0
    print(f"# {args.scenario}: ok: {run['n_steps']} steps of h = {run['h']:g} s "
          f"(t_end = {run['t_end']:g} s), nodes {', '.join(run['nodes'])}")
    print(sc.to_toml(scenario))
    return 0


def _delegate(module: str, argv: list[str]) -> int:
    import importlib

    return int(importlib.import_module(module).main(argv) or 0)


COMMANDS: tuple[tuple[str, tuple[tuple[str, str, str], ...]], ...] = (
    ("everyday commands", (
        ("run", "", "run a scenario"),
        ("check", "", "validate a scenario as run does, without running it; print it resolved"),
        ("sweep", "orchestrator.sweep", "a grid of scenarios, several runs at once"),
        ("report", "orchestrator.report", "a self-contained HTML report of a run or sweep"),
        ("fatigue", "orchestrator.fatigue_cli",
         "fatigue life of the lower arm from a finished run or a load file"),
        ("duty", "orchestrator.duty", "damage and life over a proving-ground schedule of events"),
        ("scope", "orchestrator.scope", "watch a run live in the browser (plots, damage map)"),
        ("part", "orchestrator.studies.part_check",
         "a part file's model card: mass, modes, stresses, hot spots, mesh convergence"),
        ("corner", "orchestrator.studies.corner_check",
         "a corner file's kinematic and compliance curves and equivalent quarter car"))),
    ("results and model cards", (
        ("runs", "orchestrator.runs", "list runs and their state from the run folders"),
        ("ride", "orchestrator.ride", "ride metrics of runs, side by side"),
        ("export", "orchestrator.export",
         "a run's table from its journal, or as MDF 4 / RPC III / CSV / Parquet (streamed)"),
        ("pseudo-damage", "orchestrator.pseudo_damage_cli",
         "pseudo-damage of every load channel of runs or load files, side by side"),
        ("arm", "orchestrator.studies.arm_card",
         "the lower arm's model card (mass, modes, stresses)"),
        ("equivalent-lumped", "orchestrator.studies.equivalent_lumped",
         "equivalent lumped quarter car of the realistic corner (log decrement)"))),
    ("plumbing (several machines, the bus, other tools)", (
        ("node", "orchestrator.node_main", "start one node (it may run on another machine)"),
        ("router", "orchestrator.router", "a Zenoh router (for multi-machine runs)"),
        ("cluster", "orchestrator.cluster", "a local Dask scheduler and workers for sweeps"),
        ("tap", "orchestrator.tap", "print the messages of a running run, live"),
        ("replay", "orchestrator.replay", "republish a recorded journal on the bus"),
        ("export-fmu", "orchestrator.export_fmu", "the scenario's control law as an FMI FMU"))),
)
"""The subcommands by ``--help`` group: (name, the module that parses its own arguments ("":
run and check, parsed here), one-line help)."""


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("suscosim")
    except PackageNotFoundError:  # run from a source tree that was never installed
        return "unknown (not installed)"


def _grouped_help() -> str:
    width = max(len(c[0]) for _, cmds in COMMANDS for c in cmds) + 2
    out = []
    for title, cmds in COMMANDS:
        out.append(f"{title}:")
        out += [f"  {name:<{width}}{text}" for name, _m, text in cmds]
        out.append("")
    out.append("'suscosim COMMAND --help' for a command's options. Exit codes: 0 done, 1 the "
               "run failed, 2 bad input.")
    return "\n".join(out)


def _add_scenario_arguments(p: argparse.ArgumentParser, optional: bool = False) -> None:
    if optional:  # run --resume / --fork take the run folder's scenario
        p.add_argument("scenario", nargs="?", help="scenario TOML file (none with --resume "
                                                   "or --fork)")
    else:
        p.add_argument("scenario", help="scenario TOML file")
    p.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="override a scenario value (TOML), e.g. --set run.h=0.002; a whole "
                        "table: --set 'controller={law=\"skyhook\", c_sky=2500.0}'")
    p.add_argument("--mode", choices=["distributed", "monolithic", "reference"],
                   help="distributed: one process per node over Zenoh; monolithic: the same "
                        "as --inprocess; reference: SciPy solve_ivp of the lumped model")
    p.add_argument("--inprocess", action="store_true",
                   help="run.transport = \"inprocess\": the node models stepped in this "
                        "process, no bus (tables bit-identical to the distributed run's)")


def _mode_overrides(args: argparse.Namespace) -> list[str]:
    out = [f'run.mode="{args.mode}"'] if args.mode else []
    if args.mode == "distributed":
        out.append('run.transport="zenoh"')
    if getattr(args, "inprocess", False):
        out.append('run.transport="inprocess"')
    return out


def build_parser() -> argparse.ArgumentParser:
    ap = ArgumentParser(prog="suscosim", description="suscosim: a distributed co-simulation "
                        "of semi-active suspensions and the fatigue of their parts",
                        formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--version", action="version", version=f"suscosim {_version()}")
    sub = ap.add_subparsers(dest="command", required=True, metavar="COMMAND",
                            help="one of the commands below")
    helps = {name: text for _, cmds in COMMANDS for name, _m, text in cmds}
    r = sub.add_parser("run", description=helps["run"])
    _add_scenario_arguments(r, optional=True)
    r.add_argument("--out", help="run folder (default runs/<run id>)")
    r.add_argument("--resume", metavar="RUN_DIR",
                   help="continue a run that was stopped from its last complete checkpoint "
                        "(run.checkpoint_every_s): same scenario, same folder; the results "
                        "equal the uninterrupted run's")
    r.add_argument("--fork", metavar="RUN_DIR@T",
                   help="a new run from the checkpoint of RUN_DIR at T [s], with --set "
                        "applied (the control may change; vehicle, tyre, road and step not)")
    zo.add_connect_argument(r, "Zenoh router endpoint (default: embedded peer mode on loopback)",
                            metavar=None)
    zo.add_listen_argument(r, "endpoint the orchestrator listens on (default: a free loopback "
                              "port)", metavar=None)
    zo.add_lowlatency_argument(r, "Zenoh's low-latency transport for the local nodes' sessions "
                                  "(default: on, off with --zenoh-config; ~15-30 %% faster; the "
                                  "orchestrator's own session is universal)", negatable=True)
    r.add_argument("--pin", choices=PIN_MODES, default="auto",
                   help="pin the local node processes to cores (auto: on machines of 2-4 "
                        "cores; see orchestrator/placement.py)")
    r.add_argument("--external", action="append", metavar="NODE",
                   help="do not start NODE here: it is started elsewhere with 'suscosim node'")
    zo.add_config_argument(r)
    r.add_argument("--quiet", action="store_true", help="no progress bar")
    r.set_defaults(func=cmd_run)
    c = sub.add_parser("check", description=helps["check"])
    _add_scenario_arguments(c)
    c.add_argument("--json", action="store_true",
                   help="print the resolved scenario as JSON (as a run's scenario.json)")
    c.set_defaults(func=cmd_check)
    for name, module, text in (c for _, cmds in COMMANDS for c in cmds if c[1]):
        p = sub.add_parser(name, description=text, add_help=False)
        p.add_argument("rest", nargs=argparse.REMAINDER)
        p.set_defaults(func=None, module=module)
    ap.epilog = _grouped_help()
    return ap


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    ap = build_parser()
    # parse_known_args: a delegated subcommand's leading options ('router --listen X') are
    # not taken by its REMAINDER argument; they come back here, in order, before the rest.
    args, unknown = ap.parse_known_args(argv)
    if unknown and args.func is not None:
        ap.error(f"unrecognized arguments: {' '.join(unknown)}")
    try:
        return _delegate(args.module, unknown + args.rest) if args.func is None else args.func(args)
    except SuscosimError as exc:
        print(error_line("suscosim", str(exc)), file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print(error_line("suscosim", "interrupted"), file=sys.stderr)
        return 130
    except BrokenPipeError:  # output piped into e.g. `head`: not an error of ours
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except Exception as exc:  # a bug: one line for the user, the details for a report
        import traceback

        print(error_line("suscosim", f"internal error: {type(exc).__name__}: {exc}"),
              file=sys.stderr)
        if os.environ.get("SUSCOSIM_DEBUG"):
            traceback.print_exc()
        return 1
