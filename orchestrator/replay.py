"""``suscosim replay JOURNAL``: republish a recorded journal on the bus, as if the run were live
(docs/tap_replay.md): every data record on ``suscosim/<run>/<node>/<channel>`` with the bytes
the recorder received, in order, at the recorded pace (``--speed X``) or at once (``--fast``);
run id ``<original>-replay`` by default. Without ``--connect``/``--listen`` it listens on
``tcp/127.0.0.1:7447``. Exit codes: 0 replayed, 1 the endpoint cannot be reached (client
mode), 2 bad input, 130 interrupted.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Iterator
from functools import partial
from pathlib import Path
from typing import Any

from cosim import keys
from cosim.errors import ScenarioError, WireError
from cosim.wire import decode
from cosim.zenoh_options import SessionOpenError, add_zenoh_arguments, open_session

from .cli_util import add_pace_arguments, fail, pace_factor, parse_args

_fail = partial(fail, "suscosim replay")
DEFAULT_LISTEN = "tcp/127.0.0.1:7447"
LINGER_S = 0.5  # [s] open after the last message, so Zenoh sends what it still holds


class ReplayInputError(ValueError):
    """Bad replay input: exit code 2 with this message."""


Record = tuple[str, str, bytes, float]
"""(node, channel, raw message, t [s])."""


def _journal_path(path: str | Path) -> Path:
    p = Path(path)
    if p.is_dir():
        p = p / "journal.msgpack"
    if not p.is_file():
        raise ReplayInputError(f"{p}: no such journal file")
    return p


def _records(p: Path, counts: dict[str, Any] | None = None) -> Iterator[Record]:
    """The journal's data records (node, channel, raw, t), streamed; counts in ``counts``."""
    from cosim.journal import JournalReader

    try:
        reader = JournalReader(p)
    except (OSError, ValueError) as exc:
        raise ReplayInputError(str(exc)) from None
    skipped = 0
    for channel, raw in reader:
        parts = channel.split("/")
        try:
            if len(parts) != 2:
                raise ValueError(channel)
            keys.check_name("node", parts[0])
            keys.check_name("channel", parts[1])
            t = decode(raw).t
        except (ValueError, ScenarioError, WireError):
            skipped += 1
            continue
        yield parts[0], parts[1], raw, t
    if counts is not None:
        counts.update(run_id=reader.run_id, skipped=skipped, problem=reader.contents().problem)


class Recorded:
    """A journal's records, streamed at each iteration; counted once (``count``, ``channels``)."""

    def __init__(self, path: str | Path) -> None:
        self.path = _journal_path(path)
        counts: dict[str, Any] = {}
        self.count, self.channels = 0, set()
        self.t_first = self.t_last = 0.0
        for node, channel, _raw, t in _records(self.path, counts):
            if not self.count:
                self.t_first = t
            self.count += 1
            self.channels.add((node, channel))
            self.t_last = t
        self.run_id: str = counts["run_id"]
        self.skipped: int = counts["skipped"]
        self.problem: str = counts["problem"]

    def __iter__(self) -> Iterator[Record]:
        return _records(self.path)

    def __len__(self) -> int:
        return self.count


def _wait_for_subscriber(pubs: list[Any], wait_s: float) -> bool:
    owners = [getattr(put, "__self__", None) for put in pubs]
    objs = [o for o in owners if o is not None and hasattr(o, "matching_status")]
    deadline = time.monotonic() + wait_s
    while time.monotonic() < deadline:
        if not objs:  # no matching API: give discovery a moment
            time.sleep(min(1.0, wait_s))
            return False
        if any(o.matching_status.matching for o in objs):
            time.sleep(0.05)  # let the other declarations of that peer arrive too
            return True
        time.sleep(0.02)
    return False


def replay(bus: Any, run_id: str, records: Recorded, speed: float | None,
           wait_s: float = 5.0, log: Any = None) -> tuple[int, float]:
    """Publish ``records`` under ``run_id`` (``speed`` None: at once); (sent, wall s)."""
    log = log or (lambda text: None)
    pubs = {(n, c): bus.publisher(keys.key(run_id, n, c)) for n, c in sorted(records.channels)}
    if wait_s > 0 and not _wait_for_subscriber(list(pubs.values()), wait_s):
        log(f"no subscriber after {wait_s:g} s: publishing anyway")
    t_first: float | None = None
    start = time.monotonic()
    sent = 0
    for node, channel, raw, t in records:
        if t_first is None:
            t_first = t
        if speed is not None:
            ahead = start + (t - t_first) / speed - time.monotonic()
            if ahead > 0.0005:
                time.sleep(ahead)
        pubs[node, channel](raw)
        sent += 1
    return sent, time.monotonic() - start


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="suscosim replay",
                                 description="republish a recorded journal on the bus")
    ap.add_argument("journal", help="journal.msgpack, or a run folder holding one")
    ap.add_argument("--run", metavar="ID", help="run id to publish under "
                    "(default: <original>-replay)")
    add_pace_arguments(ap, speed_help="pace factor against the recorded time (default 1 = real "
                                      "time)", fast_help="as fast as possible")
    ap.add_argument("--wait", type=float, default=5.0, metavar="S",
                    help="wait up to S s for a subscriber before publishing (default 5)")
    add_zenoh_arguments(
        ap, connect_help="Zenoh endpoint to connect to (a run's, a router's, a tap's)",
        listen_help=f"endpoint to listen on (default {DEFAULT_LISTEN} when no --connect)",
        lowlatency_help="Zenoh low-latency transport (negotiated per link: peers without it "
                        "still connect)")
    return ap


def main(argv: list[str] | None = None) -> int:
    args = parse_args(build_parser(), argv)
    if isinstance(args, int):
        return args
    if args.wait < 0:
        return _fail(f"--wait {args.wait:g}: expected a time >= 0 s")
    try:
        records = Recorded(args.journal)
    except ReplayInputError as exc:
        return _fail(str(exc))
    original = records.run_id
    if not records.count:
        return _fail(f"{args.journal}: the journal holds no data message to replay")
    run_id = args.run or f"{original}-replay"
    try:
        keys.check_name("run", run_id)
    except ScenarioError:
        return _fail(f"run id {run_id!r}: 1-64 letters, digits, '_', '.', '-' (give one with "
                     "--run)")
    if records.problem:
        print(f"suscosim replay: note: {records.problem}; replaying the {len(records)} records "
              "before it", file=sys.stderr)
    if records.skipped:
        print(f"suscosim replay: note: skipped {records.skipped} undecodable record(s)",
              file=sys.stderr)
    connect = list(args.connect or [])
    listen = args.listen or (None if connect else [DEFAULT_LISTEN])
    try:
        bus, mode = open_session(args, connect, listen)
    except SessionOpenError as exc:
        return _fail(exc.message(f"listen {listen or 'loopback'}, connect {connect}"), exc.code)
    where = ", ".join(connect or listen or [])
    pace_text = "as fast as possible" if args.fast else f"at {args.speed:g}x the recorded pace"
    print(f"suscosim replay: {len(records)} messages on {len(records.channels)} channels of run "
          f"{original} as suscosim/{run_id}/** via {where} ({mode} session), {pace_text}",
          file=sys.stderr, flush=True)
    try:
        sent, wall = replay(bus, run_id, records, pace_factor(args),
                            args.wait, log=lambda text: print(f"suscosim replay: {text}",
                                                              file=sys.stderr, flush=True))
        time.sleep(LINGER_S)
    except KeyboardInterrupt:
        print("suscosim replay: interrupted", file=sys.stderr)
        return 130
    finally:
        bus.close()
    print(f"replayed {sent} messages as run {run_id}: {records.t_last - records.t_first:.4g} s "
          f"of run time in {wall:.3g} s wall")
    return 0
