"""``suscosim tap``: the command (options, the Zenoh subscriber, the display loop)."""

from __future__ import annotations

import argparse
import queue
import shutil
import signal
import sys
import time
from functools import partial
from typing import Any

from cosim.step_message import step_keyexprs
from cosim.zenoh_options import SessionOpenError, add_zenoh_arguments, open_session

from ..cli_util import fail, parse_args
from .stats import CsvSink, Tap
from .target import DEFAULT_ENDPOINT, TapInputError, Target, resolve_target

_fail = partial(fail, "suscosim tap")


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="suscosim tap",
                                 description="print the messages of a running run, live")
    ap.add_argument("run", nargs="?", default=None,
                    help="run id, '*' (every run, the default) or a run folder")
    ap.add_argument("pattern", nargs="?", default=None,
                    help="NODE/CHANNEL with * and ** wildcards (default: everything)")
    ap.add_argument("--csv", metavar="FILE", help="append data messages to this CSV file")
    ap.add_argument("--duration", type=float, metavar="S", help="stop after S seconds")
    ap.add_argument("--count", type=int, metavar="N", help="stop after N data messages")
    ap.add_argument("--raw", action="store_true", help="one line per message, no table")
    ap.add_argument("--interval", type=float, default=1.0, metavar="S",
                    help="display refresh period [s] (default 1)")
    add_zenoh_arguments(
        ap, connect_help=f"Zenoh endpoint of the run (default: the run folder's, else "
                         f"{DEFAULT_ENDPOINT})",
        lowlatency_help="Zenoh low-latency transport (as the run uses it, read from run.json "
                        "when RUN is a run folder; negotiated per link, so a tap without it "
                        "still connects)")
    return ap


def main(argv: list[str] | None = None) -> int:
    args = parse_args(build_parser(), argv)
    if isinstance(args, int):
        return args
    if args.duration is not None and args.duration <= 0:
        return _fail(f"--duration {args.duration:g}: expected a time > 0 s")
    if args.count is not None and args.count <= 0:
        return _fail(f"--count {args.count}: expected a number of messages > 0")
    if args.interval <= 0:
        return _fail(f"--interval {args.interval:g}: expected a period > 0 s")
    try:
        target = resolve_target(args.run, args.pattern, args.connect)
        sink = CsvSink(args.csv) if args.csv else None
    except TapInputError as exc:
        return _fail(str(exc))
    try:
        return _tap(args, target, sink)
    finally:
        if sink is not None:
            sink.close()


def _tap(args: argparse.Namespace, target: Target, sink: CsvSink | None) -> int:
    try:
        bus, mode = open_session(args, target.endpoints, args.listen,
                                 lowlatency=target.lowlatency, wait=True)
    except SessionOpenError as exc:
        return _fail(exc.message(", ".join(target.endpoints)), exc.code)
    inbox: queue.SimpleQueue[tuple[str, bytes, float]] = queue.SimpleQueue()
    clock = time.monotonic
    stop: list[str] = []

    def on_term(signum: int, _frame: Any) -> None:
        stop.append(signal.Signals(signum).name)

    old_term = signal.signal(signal.SIGTERM, on_term)
    tap = Tap(target.keyexpr, sink, args.raw)
    tty = sys.stdout.isatty() and not args.raw
    try:
        for kx in step_keyexprs(target.keyexpr):  # a channel's messages come in steps
            bus.subscribe(kx, lambda key, raw: inbox.put((key, raw, clock())))
        where = ", ".join(target.endpoints) + (f" (from {target.source})" if target.source else "")
        if target.note:
            print(f"suscosim tap: note: {target.note}", file=sys.stderr)
        print(f"suscosim tap: tapping {target.keyexpr} via {where} ({mode} session)",
              file=sys.stderr, flush=True)
        t0 = clock()
        end = t0 + args.duration if args.duration else float("inf")
        next_show, warned = t0 + args.interval, False
        while not stop:
            now = clock()
            if now >= end:
                break
            try:
                key, raw, at = inbox.get(timeout=max(0.0, min(next_show, end) - now))
            except queue.Empty:
                pass
            else:
                msg = tap.handle(key, raw, at)
                if args.count and msg is not None and msg.kind == "data" and tap.data >= args.count:
                    break
                if clock() < next_show:
                    continue
            now = clock()
            if now >= next_show:
                next_show = now + args.interval
                tap.update_rates(now)
                if sink is not None:
                    sink.flush()
                if not warned and not tap.stats and now - t0 > 2.0:
                    warned = True
                    if not bus.linked():  # a ZenohBus or a LateBus
                        print(f"suscosim tap: no peer reachable at {', '.join(target.endpoints)}"
                              " yet (is a run listening there? see 'suscosim runs')",
                              file=sys.stderr, flush=True)
                if not args.raw:
                    _show(tap, tty)
    except KeyboardInterrupt:
        pass
    finally:
        signal.signal(signal.SIGTERM, old_term)
        bus.close()
    if sink is not None:
        sink.flush()
    if not args.raw:
        if tty:
            sys.stdout.write("\x1b[H\x1b[2J")
        print(f"{target.keyexpr}\n{tap.table(final=True)}")
    print(tap.summary(), flush=True)
    return 0


def _show(tap: Tap, tty: bool) -> None:
    if not tap.stats and not tty:
        return
    if tty:
        width = shutil.get_terminal_size().columns
        sys.stdout.write("\x1b[H\x1b[2J" + f"tapping {tap.keyexpr}  (Ctrl-C to stop)\n"
                         + tap.table(width) + "\n")
    else:
        sys.stdout.write(tap.table() + "\n\n")
    sys.stdout.flush()
