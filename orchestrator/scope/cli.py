"""``suscosim scope``: the command (arguments, the run's source, the server's lifetime)."""

from __future__ import annotations

import argparse
import signal
import sys
import threading
import time
from functools import partial
from pathlib import Path
from typing import Any

from cosim import keys
from cosim.errors import ScenarioError
from cosim.run_folder import read_json
from cosim.wire import decode
from cosim.zenoh_options import SessionOpenError, add_zenoh_arguments, open_session

from ..cli_util import add_pace_arguments, fail, pace_factor, parse_args
from .state import DEFAULT_CHANNELS, ScopeInputError, ScopeState, Selection

_fail = partial(fail, "suscosim scope")

DEFAULT_PORT = 8470


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(
        prog="suscosim scope",
        description="watch a run live in the browser: time plots, progress, node states, "
                    "the arm's damage map")
    ap.add_argument("run", metavar="RUN_OR_RUN_DIR",
                    help="a run folder (live while it runs, replayed from its journal once "
                         "it has ended) or a run id (live, at --connect)")
    ap.add_argument("--channels", nargs="+", action="extend", metavar="PATTERN",
                    help="NODE/CHANNEL[/FIELD] with * wildcards (default: "
                         f"{' '.join(DEFAULT_CHANNELS)})")
    ap.add_argument("--port", type=int, default=DEFAULT_PORT,
                    help=f"HTTP port (default {DEFAULT_PORT}; 0: a free one)")
    ap.add_argument("--host", default="127.0.0.1",
                    help="address to serve on (default loopback only)")
    ap.add_argument("--open", action="store_true", help="open the page in a web browser")
    add_pace_arguments(ap, speed_help="replay pace against the recorded time (default 1 = real "
                                      "time)", fast_help="replay as fast as possible")
    ap.add_argument("--replay", action="store_true",
                    help="replay the run folder's journal even if the run is still going")
    ap.add_argument("--duration", type=float, metavar="S",
                    help="stop after S seconds (default: on Ctrl-C or SIGTERM)")
    ap.add_argument("--buffer", type=int, default=20000, metavar="N",
                    help="samples kept per line (default 20000)")
    add_zenoh_arguments(
        ap, connect_help="Zenoh endpoint of the run: a router's for a run on other machines "
                         "(default: the run folder's run.json, else tcp/127.0.0.1:7447)",
        lowlatency_help="Zenoh low-latency transport (default: as run.json says)")
    return ap


def main(argv: list[str] | None = None) -> int:
    args = parse_args(build_parser(), argv)
    if isinstance(args, int):
        return args
    if not 0 <= args.port <= 65535:
        return _fail(f"--port {args.port}: expected 0-65535")
    if args.duration is not None and args.duration <= 0:
        return _fail(f"--duration {args.duration:g}: expected a time > 0 s")
    if args.buffer < 100:
        return _fail(f"--buffer {args.buffer}: expected at least 100 samples")
    try:
        return _scope(args, Selection(args.channels))
    except ScopeInputError as exc:
        return _fail(str(exc))


def _scope(args: argparse.Namespace, selection: Selection) -> int:
    from .server import ScopeServer
    from .sources import DamageMap, wants_map

    folder = Path(args.run) if Path(args.run).is_dir() else None
    scenario = read_json(folder / "scenario.json") if folder else None
    scenario = scenario if isinstance(scenario, dict) else None
    replay = folder is not None and (args.replay or (folder / "summary.json").exists())
    bus = None
    if replay:
        from ..replay import Recorded, ReplayInputError

        assert folder is not None  # replay is only ever set for a run folder
        try:
            records = Recorded(folder)  # streamed from the journal (#32): not held whole
            run_id, problem = records.run_id, records.problem
        except ReplayInputError as exc:
            raise ScopeInputError(f"{exc} (a finished run is replayed from its journal)") from None
        if problem:
            print(f"suscosim scope: note: {problem}", file=sys.stderr)
        where = f"replay of {folder / 'journal.msgpack'} at " + \
            ("full speed" if args.fast else f"{args.speed:g}x")
    else:
        from ..tap import TapInputError, resolve_target

        if folder is None and ("/" in args.run or args.run in (".", "..")):
            raise ScopeInputError(f"{args.run}: no such run folder")
        try:
            target = resolve_target(args.run, None, args.connect)
        except TapInputError as exc:
            raise ScopeInputError(str(exc)) from None
        run_id = target.keyexpr.split("/")[1]
        if run_id == "*":
            raise ScopeInputError(f"{args.run!r}: give one run (a run id or a run folder)")
        try:
            keys.check_name("run", run_id)
        except ScenarioError:
            raise ScopeInputError(f"{args.run!r}: not a run id or a run folder") from None
        try:
            bus, mode = open_session(args, target.endpoints, args.listen,
                                     lowlatency=target.lowlatency, wait=True)
        except SessionOpenError as exc:
            return _fail(exc.message(", ".join(target.endpoints)), exc.code)
        if target.note:
            print(f"suscosim scope: note: {target.note}", file=sys.stderr)
        if scenario is None:  # a bare run id: ask the run's orchestrator (as its nodes do)
            scenario = _query_scenario(bus, run_id)
        where = f"live via {', '.join(target.endpoints)} ({mode} session)"
    run_cfg = (scenario or {}).get("run") or {}
    state = ScopeState(run_id, selection, source="replay" if replay else "live",
                       n_steps=run_cfg.get("n_steps"), h=run_cfg.get("h"),
                       nodes=list(run_cfg.get("nodes") or []), max_samples=args.buffer)
    journal = folder / "journal.msgpack" if folder is not None and not replay else None
    damage = DamageMap(scenario, state, journal=journal) \
        if scenario and wants_map(scenario) else None
    try:
        server = ScopeServer(state, args.host, args.port)
    except OSError as exc:
        if bus is not None:
            bus.close()
        return _fail(f"cannot serve on {args.host}:{args.port}: {exc.strerror or exc} "
                     "(another scope there? choose one with --port, 0 for a free port)")
    if replay:
        from .sources import JournalSource

        source: Any = JournalSource(records, state, pace_factor(args), damage, run=run_cfg)
    else:
        from .sources import LiveSource

        source = LiveSource(bus, state, damage)
    ask = None
    if not replay and scenario is None:  # the run has not started yet: ask again later
        def ask() -> bool:
            sc = _query_scenario(bus, run_id, timeout_s=0.5)
            if sc is None:
                return False
            run = sc.get("run") or {}
            state.set_scenario(run.get("n_steps"), run.get("h"), list(run.get("nodes") or []))
            if wants_map(sc):
                try:
                    source.attach(DamageMap(sc, state))
                except Exception as exc:  # a [fatigue] the engine refuses: no map, say why
                    print(f"suscosim scope: no damage map: {exc}", file=sys.stderr)
            return True
    return _serve(args, server, source, state, bus, where, ask)


def _query_scenario(bus: Any, run_id: str, timeout_s: float = 2.0) -> dict[str, Any] | None:
    try:
        raw = bus.query(keys.key(run_id, keys.ORCHESTRATOR, keys.SCENARIO), timeout=timeout_s)
        return decode(raw).d if raw is not None else None
    except Exception:  # no orchestrator answering (yet): no map, n_steps from the clock
        return None


def _serve(args: argparse.Namespace, server: Any, source: Any, state: ScopeState, bus: Any,
           where: str, ask: Any = None) -> int:
    """Serve until stopped; ``ask()`` (if given) is retried every 2 s until it is True."""
    stop = threading.Event()

    def on_term(_signum: int, _frame: Any) -> None:
        stop.set()

    def tell(serving: bool) -> bool:
        """Say once on stderr that the run ended (also when the scope stops right after)."""
        if state.run_state not in ("done", "failed"):
            return False
        print(f"suscosim scope: run {state.run_id} {state.run_state} at step {state.k}"
              + (f" (still serving {server.url}; Ctrl-C to stop)" if serving else ""),
              file=sys.stderr, flush=True)
        return True

    old_term = signal.signal(signal.SIGTERM, on_term)
    told = False
    try:
        server.start()
        source.start()
        print(f"suscosim scope: {server.url} - run {state.run_id}, {where}", flush=True)
        if args.open:
            import webbrowser

            if not webbrowser.open(server.url):
                print(f"suscosim scope: no browser found; open {server.url}", file=sys.stderr)
        end = time.monotonic() + args.duration if args.duration else float("inf")
        next_ask = time.monotonic()
        while not stop.wait(0.2) and time.monotonic() < end:
            if ask is not None and time.monotonic() >= next_ask:
                ask = None if ask() else ask
                next_ask = time.monotonic() + 2.0
            told = told or tell(serving=True)
    except KeyboardInterrupt:
        pass
    finally:
        signal.signal(signal.SIGTERM, old_term)
        if not told:  # the run ended since the last look
            tell(serving=False)
        source.close()
        server.close()
        if bus is not None:
            bus.close()
    return 0
