"""``suscosim tap``: watch the messages of a running run (or of a replay), live.

    suscosim tap [RUN] [PATTERN] [--connect EP ...] [--listen EP ...] [--csv FILE]
                 [--duration S] [--count N] [--raw] [--interval S] [--lowlatency]
                 [--mode auto|peer|client] [--zenoh-config FILE]

The tap is a plain Zenoh subscriber on ``suscosim/<RUN>/<PATTERN>``: it declares no
liveliness token and sends nothing, so the run neither waits for it nor sees it. Its callback
only queues the bytes (it never blocks Zenoh, so it never slows the run's publishers down);
decoding and display happen in the main thread.

* ``RUN``: a run id, ``*`` (every run: the default), or a run folder (then the run id and
  the endpoint come from its ``run.json``, written by ``suscosim run``).
* ``PATTERN`` (default ``**``): ``<node>/<channel>`` with ``*`` for any one name and ``**``
  for anything, e.g. ``plant/state``, ``*/force``, ``plant/*``; a single name is a node
  (``plant`` = ``plant/*``). A first argument with a ``/`` that is no folder is a pattern, so
  ``suscosim tap plant/state`` taps that channel of every run.
* Endpoint: ``--connect`` (repeatable); default the run folder's (its router if it has
  one, else the orchestrator's listen endpoint), else ``tcp/127.0.0.1:7447`` -- so a run
  started with ``--listen tcp/127.0.0.1:7447`` is tapped by a bare ``suscosim tap``.
  ``suscosim runs`` shows where each running run listens.
* Session mode (``--mode auto``): a Zenoh peer when every endpoint is on loopback (it joins
  the run's mesh, data come straight from the nodes), a client otherwise (everything comes
  through the one router or peer it connects to: what works from another machine).

Display: per key, the message count and rate [msg/s], the last step ``k``, its time ``t``
[s] and the last values (arrays shortened), redrawn every ``--interval`` s (on a terminal;
otherwise printed as successive blocks). ``--raw`` prints every message as one line instead.
Messages that do not decode (foreign schema version, not msgpack) are counted and reported,
never fatal. ``--csv FILE`` appends one row per data message: ``key,k,t`` and the fields
(lists flattened to ``name[i]``); when a channel with new fields appears the file is
rewritten with the wider header (older rows get empty cells).

Stops on Ctrl-C, SIGTERM, after ``--duration`` s or after ``--count`` data messages, with a
final summary line ``tap: M messages (D data, C control), U undecodable on K key(s)``.
Exit codes: 0 done, 1 the endpoint cannot be reached (client mode, after 10 s), 2 bad input
(run id, pattern, CSV file, endpoint).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import queue
import re
import shutil
import signal
import socket
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO

from cosim import keys
from cosim.errors import ScenarioError, WireError
from cosim.wire import Message, decode

DEFAULT_ENDPOINT = "tcp/127.0.0.1:7447"
_CHUNK = re.compile(r"^(\*\*?|[A-Za-z0-9][A-Za-z0-9_.-]{0,63})$")


class TapInputError(ValueError):
    """Bad tap input (run, pattern, file, endpoint): exit code 2 with this message."""


# ---- key expressions ---------------------------------------------------------------------
def channel_keyexpr(pattern: str | None) -> str:
    """``plant/state``, ``*/force``, ``plant`` (a node), ``**`` -> the ``node/channel`` part."""
    pattern = (pattern or "**").strip().strip("/")
    chunks = pattern.split("/") if pattern else ["**"]
    for c in chunks:
        if not _CHUNK.match(c):
            raise TapInputError(f"pattern {pattern!r}: chunk {c!r} is not a name, '*' or '**'")
    if len(chunks) == 1 and chunks[0] not in ("**",):
        chunks = [chunks[0], "*"] if chunks[0] != "*" else ["*", "*"]
    if len(chunks) > 2 and "**" not in chunks:
        raise TapInputError(f"pattern {pattern!r}: expected NODE/CHANNEL (two names at most)")
    return "/".join(chunks)


def tap_keyexpr(run: str | None, pattern: str | None) -> str:
    """``suscosim/<run or *>/<pattern>``."""
    run = run or "*"
    if run != "*":
        try:
            keys.check_name("run", run)
        except ScenarioError:
            raise TapInputError(f"run {run!r}: not a run id (letters, digits, '_', '.', '-'), "
                                "'*' or a run folder") from None
    return f"{keys.PREFIX}/{run}/{channel_keyexpr(pattern)}"


@dataclass
class Target:
    """What to tap and where: resolved from the RUN and PATTERN arguments."""

    keyexpr: str
    endpoints: list[str]
    lowlatency: bool = False
    source: str = ""
    note: str = ""


def is_loopback(ep: str) -> bool:
    """Whether a Zenoh endpoint (``tcp/127.0.0.1:7447``) is on this machine's loopback."""
    host = ep.split("/", 1)[-1].rsplit(":", 1)[0].strip("[]").split("#")[0]
    return host in ("localhost", "::1") or host.startswith("127.")


def session_mode(mode: str, connect: list[str], listen: list[str] | None) -> str:
    """``auto``: a peer (joins the run's mesh directly) when every endpoint is on loopback
    or the session listens; a client (everything through the one endpoint) otherwise: a peer
    on another machine is not relayed by a router, and the run's peers, listening on their
    loopback, cannot connect back to it."""
    if mode != "auto":
        return mode
    return "peer" if listen or all(is_loopback(e) for e in connect) else "client"


def apply_mode(conf: Any, mode: str, connect_timeout_ms: int = 10000) -> Any:
    """Make a :func:`cosim.bus.zenoh_config` a client's (no listening; keep trying to reach
    the endpoint for ``connect_timeout_ms``), or leave it a peer's."""
    if mode == "client":
        conf.insert_json5("mode", '"client"')
        conf.insert_json5("listen/endpoints", "[]")
        conf.insert_json5("connect/timeout_ms", str(int(connect_timeout_ms)))
    return conf


def _local(ep: str) -> str:
    """A listen endpoint on every interface is reached on loopback from this machine."""
    for anyaddr in ("0.0.0.0", "[::]"):
        ep = ep.replace(f"/{anyaddr}:", "/127.0.0.1:")
    return ep


def resolve_target(run: str | None, pattern: str | None,
                   connect: list[str] | None) -> Target:
    """Resolve RUN (id, ``*`` or a run folder), PATTERN and endpoints."""
    endpoints: list[str] = list(connect or [])
    lowlatency, source, note = False, "", ""
    if run and Path(run).is_dir():
        folder = Path(run)
        if (folder / "summary.json").exists():
            note = f"{folder} has a summary.json: that run has ended (tapping anyway)"
        meta: dict[str, Any] = {}
        for name in ("run.json", "scenario.json"):
            try:
                meta[name] = json.loads((folder / name).read_text())
            except (OSError, ValueError):
                pass
        if not meta:
            raise TapInputError(f"{folder}: not a run folder (no run.json or scenario.json)")
        rj = meta.get("run.json") or {}
        run = rj.get("run_id") or ((meta.get("scenario.json") or {}).get("run") or {}).get("id")
        if not run:
            raise TapInputError(f"{folder}: no run id in run.json or scenario.json")
        eps = rj.get("endpoints") or {}
        if not endpoints:  # through the run's router if it has one, else to the orchestrator
            endpoints = list(eps.get("connect", [])) or [_local(e) for e in eps.get("listen", [])]
            source = f"{folder / 'run.json'}" if endpoints else ""
            host = rj.get("host")
            if host and host != socket.gethostname() and endpoints and \
                    all(is_loopback(e) for e in endpoints):
                note = (f"the run is on host {host} and listens on loopback only: not "
                        "reachable from here (start it with --listen tcp/0.0.0.0:PORT)")
        lowlatency = bool(rj.get("lowlatency", False))
        if rj and not endpoints:
            raise TapInputError(f"{folder}: run.json records no endpoint (a "
                                f"{rj.get('mode') or 'non-distributed'} run has no bus to tap)")
    elif run and "/" in run:
        if pattern:
            raise TapInputError(f"{run}: not a run folder")
        run, pattern = "*", run
    if not endpoints:
        endpoints, source = [DEFAULT_ENDPOINT], "default"
    return Target(tap_keyexpr(run, pattern), endpoints, lowlatency, source, note)


# ---- formatting ----------------------------------------------------------------------------
def fmt_value(value: Any, max_items: int = 4) -> str:
    """A number as %.5g; a list shortened to its first items and its length."""
    if isinstance(value, bool) or value is None:
        return str(value)
    if isinstance(value, int | float):
        return f"{value:.5g}"
    if isinstance(value, list | tuple):
        items = [fmt_value(v) for v in value[:max_items]]
        if len(value) > max_items:
            return "[" + ", ".join(items[:max_items - 1]) + f", ...]({len(value)})"
        return "[" + ", ".join(items) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k}: {fmt_value(v)}" for k, v in list(value.items())[:3]) + \
            (", ...}" if len(value) > 3 else "}")
    text = str(value)
    return text if len(text) <= 24 else text[:21] + "..."


def fmt_fields(msg: Message) -> str:
    body = " ".join(f"{name}={fmt_value(v)}" for name, v in msg.d.items())
    return body if msg.kind == "data" else f"<{msg.kind}> {body}".rstrip()


def flatten(d: dict[str, Any]) -> dict[str, Any]:
    """Data fields as CSV columns: a list ``x`` becomes ``x[0]``, ``x[1]``, ..."""
    out: dict[str, Any] = {}
    for name, value in d.items():
        if isinstance(value, list):
            for i, v in enumerate(value):
                out[f"{name}[{i}]"] = v
        else:
            out[name] = value
    return out


# ---- CSV -------------------------------------------------------------------------------------
class CsvSink:
    """Append data rows to a CSV file whose header grows with the fields seen."""

    BASE = ["key", "k", "t"]

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.columns: list[str] = list(self.BASE)
        self.rows = 0
        try:
            with open(self.path, newline="") as f:
                header = next(csv.reader(f), None)
        except FileNotFoundError:
            header = None
        except OSError as exc:
            raise TapInputError(f"--csv {self.path}: {exc.strerror or exc}") from None
        if header:
            if header[:3] != self.BASE:
                raise TapInputError(f"--csv {self.path}: exists and is not a tap CSV "
                                    f"(header {','.join(header[:3])!r}, expected key,k,t)")
            self.columns = header
        try:
            self._f: TextIO = open(self.path, "a", newline="")
        except OSError as exc:
            raise TapInputError(f"--csv {self.path}: {exc.strerror or exc}") from None
        self._w = csv.writer(self._f)
        if not header:
            self._w.writerow(self.columns)

    def write(self, key: str, msg: Message) -> None:
        values = flatten(msg.d)
        new = [c for c in values if c not in self.columns]
        if new:
            self._widen(self.columns + new)
        row = {"key": key, "k": msg.k, "t": msg.t, **values}
        self._w.writerow([row.get(c, "") for c in self.columns])
        self.rows += 1

    def _widen(self, columns: list[str]) -> None:
        """Rewrite the file with a wider header (rare: a channel with new fields appeared)."""
        self._f.close()
        fd, tmp = tempfile.mkstemp(dir=self.path.parent, prefix=self.path.name, suffix=".tmp")
        with open(self.path, newline="") as src, os.fdopen(fd, "w", newline="") as dst:
            reader, writer = csv.reader(src), csv.writer(dst)
            next(reader, None)
            writer.writerow(columns)
            pad = [""] * (len(columns) - len(self.columns))
            for row in reader:
                writer.writerow(row + pad)
        os.replace(tmp, self.path)
        self.columns = columns
        self._f = open(self.path, "a", newline="")
        self._w = csv.writer(self._f)

    def flush(self) -> None:
        self._f.flush()

    def close(self) -> None:
        self._f.close()


# ---- statistics and display ------------------------------------------------------------------
@dataclass
class KeyStats:
    """What the tap saw on one key."""

    count: int = 0
    undecodable: int = 0
    first: float = 0.0
    last: float = 0.0
    window_count: int = 0
    window_start: float = 0.0
    rate: float = 0.0
    msg: Message | None = None
    problem: str = ""


@dataclass
class Tap:
    """Counts, last messages and rates per key; the display; the CSV."""

    keyexpr: str
    csv_sink: CsvSink | None = None
    raw: bool = False
    out: TextIO = sys.stdout
    stats: dict[str, KeyStats] = field(default_factory=dict)
    data: int = 0
    control: int = 0
    undecodable: int = 0
    last_problem: str = ""

    def handle(self, key: str, raw: bytes, now: float) -> Message | None:
        """Take one sample: decode, count, write to CSV. Never raises on bad bytes."""
        st = self.stats.get(key)
        if st is None:
            st = self.stats[key] = KeyStats(first=now, window_start=now)
        try:
            msg = decode(raw)
        except WireError as exc:
            st.undecodable += 1
            self.undecodable += 1
            st.problem = self.last_problem = str(exc)
            if self.raw:
                print(f"{_short_key(key)} UNDECODABLE ({exc}) {raw[:24].hex()}", file=self.out)
            return None
        st.count += 1
        st.window_count += 1
        st.last, st.msg = now, msg
        if msg.kind == "data":
            self.data += 1
            if self.csv_sink is not None:
                self.csv_sink.write(key, msg)
        else:
            self.control += 1
        if self.raw:
            print(f"{_short_key(key)} {msg.kind} k={msg.k} t={msg.t:.6g} "
                  f"{json.dumps(msg.d, separators=(',', ':'), default=str)}", file=self.out)
        return msg

    def update_rates(self, now: float) -> None:
        for st in self.stats.values():
            dt = now - st.window_start
            if dt > 0:
                st.rate = st.window_count / dt
            st.window_count, st.window_start = 0, now

    def table(self, width: int = 0, final: bool = False) -> str:
        """The per-key display (``final``: average rates over the whole tap)."""
        kw = max([len(_short_key(key)) for key in self.stats] + [24])
        lines = [f"{'key':<{kw}} {'count':>7} {'msg/s':>8} {'k':>7} {'t [s]':>9}  last values"]
        for key in sorted(self.stats):
            st = self.stats[key]
            if final:
                rate = (st.count - 1) / (st.last - st.first) if st.count > 1 and \
                    st.last > st.first else 0.0
            else:
                rate = st.rate
            msg = st.msg
            k = str(msg.k) if msg else "-"
            t = f"{msg.t:.4f}" if msg else "-"
            vals = fmt_fields(msg) if msg else ""
            if st.undecodable:
                vals = f"({st.undecodable} undecodable: {st.problem}) " + vals
            line = f"{_short_key(key):<{kw}} {st.count:>7} {rate:>8.1f} {k:>7} {t:>9}  {vals}"
            lines.append(line[:width or kw + 200])
        return "\n".join(lines)

    def summary(self) -> str:
        text = (f"tap: {self.data + self.control} messages ({self.data} data, {self.control} "
                f"control), {self.undecodable} undecodable on {len(self.stats)} key(s)")
        if self.undecodable:
            text += f"; last problem: {self.last_problem}"
        if self.csv_sink is not None:
            text += f"; {self.csv_sink.rows} rows -> {self.csv_sink.path}"
        return text


def _short_key(key: str) -> str:
    return key[len(keys.PREFIX) + 1:] if key.startswith(keys.PREFIX + "/") else key


# ---- the command -----------------------------------------------------------------------------
def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="suscosim tap",
                                 description="print the messages of a running run, live")
    ap.add_argument("run", nargs="?", default=None,
                    help="run id, '*' (every run, the default) or a run folder")
    ap.add_argument("pattern", nargs="?", default=None,
                    help="NODE/CHANNEL with * and ** wildcards (default: everything)")
    ap.add_argument("--connect", action="append", metavar="EP",
                    help=f"Zenoh endpoint of the run (default: the run folder's, else "
                         f"{DEFAULT_ENDPOINT})")
    ap.add_argument("--listen", action="append", metavar="EP",
                    help="endpoint to listen on (default: a free loopback port)")
    ap.add_argument("--csv", metavar="FILE", help="append data messages to this CSV file")
    ap.add_argument("--duration", type=float, metavar="S", help="stop after S seconds")
    ap.add_argument("--count", type=int, metavar="N", help="stop after N data messages")
    ap.add_argument("--raw", action="store_true", help="one line per message, no table")
    ap.add_argument("--interval", type=float, default=1.0, metavar="S",
                    help="display refresh period [s] (default 1)")
    ap.add_argument("--lowlatency", action="store_true",
                    help="Zenoh low-latency transport (as the run uses it, read from "
                         "run.json when RUN is a run folder; negotiated per link, so a tap "
                         "without it still connects)")
    ap.add_argument("--mode", choices=["auto", "peer", "client"], default="auto",
                    help="Zenoh session mode; auto: peer when every endpoint is on loopback, "
                         "client otherwise (through a router, from another machine)")
    ap.add_argument("--zenoh-config", help="Zenoh JSON5 config file (TLS, access control)")
    return ap


def _fail(message: str, code: int = 2) -> int:
    print(f"suscosim tap: {message}", file=sys.stderr)
    return code


def main(argv: list[str] | None = None) -> int:
    """Tap a run; return the exit code (0 done, 2 bad input)."""
    ap = build_parser()
    try:
        args = ap.parse_args(list(sys.argv[1:] if argv is None else argv))
    except SystemExit as exc:
        return 0 if exc.code == 0 else 2
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
    from cosim.bus import ZenohBus, zenoh_config

    if args.zenoh_config and args.mode == "auto":
        mode = "configured"  # the configuration file's mode
    else:
        mode = session_mode(args.mode, target.endpoints, args.listen)
    try:
        conf = zenoh_config(target.endpoints, args.listen,
                            lowlatency=args.lowlatency or target.lowlatency,
                            config_file=args.zenoh_config)
        bus = ZenohBus(apply_mode(conf, mode))
    except Exception as exc:  # zenoh.ZError: bad endpoint, port in use, unreachable router
        reason = " ".join(str(exc).split(" at /")[0].split())
        code = 1 if "Unable to connect" in reason else 2
        return _fail(f"cannot open a Zenoh {mode} session ({', '.join(target.endpoints)}): "
                     f"{reason}", code)
    inbox: queue.SimpleQueue[tuple[str, bytes, float]] = queue.SimpleQueue()
    clock = time.monotonic
    stop: list[str] = []

    def on_term(signum: int, _frame: Any) -> None:
        stop.append(signal.Signals(signum).name)

    old_term = signal.signal(signal.SIGTERM, on_term)
    tap = Tap(target.keyexpr, sink, args.raw)
    tty = sys.stdout.isatty() and not args.raw
    try:
        bus.subscribe(target.keyexpr, lambda key, raw: inbox.put((key, raw, clock())))
        where = ", ".join(target.endpoints) + (f" (from {target.source})" if target.source
                                               else "")
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
                if args.count and msg is not None and msg.kind == "data" and \
                        tap.data >= args.count:
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
                    if not bus.session.info.peers_zid():
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


if __name__ == "__main__":
    sys.exit(main())
