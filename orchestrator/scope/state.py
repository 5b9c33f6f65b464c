"""What the scope plots and knows about a run. Which signals: ``--channels`` patterns
``NODE/CHANNEL[/FIELD]`` (names or shell wildcards: ``plant/state``, ``*/force/F_*``), their key
expressions, and the lines (SI units) a message gives; a list field gives a line per corner;
control channels never plot. What it knows (samples: step ``k``, time ``t`` [s], value in SI
units; progress, node states, fatigue, damage map, coupling residual), behind one lock: a
source fills it, the server's threads read it (:meth:`ScopeState.snapshot`: the ``/data``
answer).
"""

from __future__ import annotations

import fnmatch
import math
import re
import threading
import time
from bisect import bisect_right
from collections import deque
from dataclasses import dataclass
from typing import Any

from cosim import keys
from cosim.channels import CORNERS
from cosim.errors import SuscosimError
from cosim.wire import Message

from ..report.signals import unit_of

DEFAULT_CHANNELS = ("plant/state/z_b", "plant/state/z_w", "plant/response/a_b",
                    "tyre_road/force/F_t", "controller/force/F_d")
CONTROL_CHANNELS = frozenset({keys.CTL, keys.RECORDS, keys.ALIVE, keys.CLOCK, keys.SCENARIO})
_PART = re.compile(r"^[A-Za-z0-9_.*?\[\]-]{1,64}$")


class ScopeInputError(SuscosimError):
    """Bad scope input (pattern, run, port, speed): exit code 2 with this message."""

    exit_code = 2


@dataclass(frozen=True)
class Pattern:
    node: str
    channel: str
    field: str | None

    @property
    def text(self) -> str:
        return "/".join(p for p in (self.node, self.channel, self.field) if p is not None)

    def keyexpr(self, run: str) -> str:
        def part(p: str) -> str:
            return "*" if any(c in p for c in "*?[") else p

        return f"{keys.PREFIX}/{run}/{part(self.node)}/{part(self.channel)}"

    def matches(self, node: str, channel: str) -> bool:
        return fnmatch.fnmatchcase(node, self.node) and fnmatch.fnmatchcase(channel, self.channel)

    def takes(self, fld: str) -> bool:
        return self.field is None or fnmatch.fnmatchcase(fld, self.field)


def parse_pattern(text: str) -> Pattern:
    parts = text.strip().strip("/").split("/")
    if len(parts) not in (2, 3) or not all(_PART.match(p) for p in parts):
        raise ScopeInputError(f"--channels {text!r}: expected NODE/CHANNEL[/FIELD], each a "
                              "name or a wildcard (*, ?), e.g. plant/state/z_b or */force")
    if parts[1] in CONTROL_CHANNELS:
        raise ScopeInputError(f"--channels {text!r}: {parts[1]!r} is a control channel, not "
                              "data")
    return Pattern(parts[0], parts[1], parts[2] if len(parts) == 3 else None)


@dataclass(frozen=True)
class Line:
    """One plotted line: ``key`` (``plant/state/z_b[0]``), its plot (``group``), label, unit."""

    key: str
    group: str
    label: str
    unit: str
    rank: int = 0  # the index of the first pattern that takes it: the plots' order


class Selection:
    def __init__(self, patterns: list[str] | None = None) -> None:
        self.patterns = [parse_pattern(p) for p in (patterns or DEFAULT_CHANNELS)]
        self._lines: dict[tuple[str, str, str, int], list[Line]] = {}

    def keyexprs(self, run: str) -> list[str]:
        return list(dict.fromkeys(p.keyexpr(run) for p in self.patterns))

    def wants(self, node: str, channel: str) -> bool:
        return channel not in CONTROL_CHANNELS and \
            any(p.matches(node, channel) for p in self.patterns)

    def lines(self, node: str, channel: str, fld: str, n: int) -> list[Line]:
        """The lines of field ``fld`` (``n``: 0 for a number, else a list's length)."""
        memo = (node, channel, fld, n)
        if memo not in self._lines:
            out: list[Line] = []
            ranks = [i for i, p in enumerate(self.patterns)
                     if p.matches(node, channel) and p.takes(fld)]
            if ranks:
                group = f"{node}/{channel}/{fld}"
                unit = unit_of(group)
                if n == 0:
                    out = [Line(group, group, fld, unit, ranks[0])]
                else:
                    names = CORNERS if n == 4 else tuple(str(i) for i in range(n))
                    out = [Line(f"{group}[{i}]", group, f"{fld} {names[i]}", unit, ranks[0])
                           for i in range(n)]
            self._lines[memo] = out
        return self._lines[memo]


# a node's state: waiting (not seen), up (token), ready, stepping, done, error, gone (token lost)
RATE_WINDOW_S = 2.0  # [s] of wall time steps/s is measured over


class _Samples:
    def __init__(self, line: Line, max_samples: int) -> None:
        self.line, self.max = line, max_samples
        self.k: list[int] = []
        self.t: list[float] = []
        self.y: list[float | None] = []

    def add(self, k: int, t: float, y: float) -> None:
        if self.k and k <= self.k[-1]:
            return  # a repeat (a second subscription matching the same key)
        self.k.append(k)
        self.t.append(t)
        self.y.append(y if math.isfinite(y) else None)  # JSON has no NaN
        if len(self.k) > 2 * self.max:
            del self.k[:-self.max], self.t[:-self.max], self.y[:-self.max]

    def since(self, k: int) -> dict[str, list]:
        i = max(bisect_right(self.k, k), len(self.k) - self.max)
        return {"k": self.k[i:], "t": self.t[i:], "y": self.y[i:]}


class ScopeState:
    """The run as the scope sees it (thread-safe)."""

    def __init__(self, run_id: str, selection: Selection, *, source: str = "live",
                 n_steps: int | None = None, h: float | None = None,
                 nodes: list[str] | None = None, max_samples: int = 20000) -> None:
        self.run_id, self.selection, self.source = run_id, selection, source
        self.n_steps, self.h = n_steps, h
        self.max_samples = max_samples
        self._lock = threading.Lock()
        self._lines: dict[str, _Samples] = {}
        self._nodes: dict[str, dict[str, Any]] = {
            n: {"state": "waiting", "k": -1} for n in (nodes or [])}
        self.k, self.t = -1, 0.0
        self.run_state = "waiting"  # waiting | stepping | done | failed
        self.reason = ""
        self.messages = 0
        self.undecodable = 0
        self._rate: deque[tuple[float, int]] = deque()
        self.fatigue: dict[str, Any] | None = None  # from the fatigue node's fatigue/damage
        self.damage_map: dict[str, Any] | None = None  # per-node damage (orchestrator.scope.damage)
        self.map_geometry: dict[str, Any] | None = None
        self._coupling = _Coupling(max_samples)

    def add_data(self, node: str, channel: str, msg: Message, now: float | None = None) -> None:
        if msg.k < 0:
            return
        with self._lock:
            self.messages += 1
            for fld, v in msg.d.items():
                if isinstance(v, bool):
                    continue
                if isinstance(v, int | float):
                    vals = [float(v)]
                    lines = self.selection.lines(node, channel, fld, 0)
                elif isinstance(v, list) and v and all(
                        isinstance(x, int | float) and not isinstance(x, bool) for x in v):
                    vals = [float(x) for x in v]
                    lines = self.selection.lines(node, channel, fld, len(v))
                else:
                    continue
                for line, y in zip(lines, vals, strict=False):
                    s = self._lines.get(line.key)
                    if s is None:
                        s = self._lines[line.key] = _Samples(line, self.max_samples)
                    s.add(msg.k, msg.t, y)
            self._node(node, "stepping", msg.k)
            self._advance(msg.k, msg.t, time.monotonic() if now is None else now)

    def node_event(self, node: str, state: str, k: int = -1, t: float = 0.0,
                   info: str = "", now: float | None = None) -> None:
        with self._lock:
            self._node(node, state, k, info)
            if state in ("stepping", "done") and k >= 0:
                self._advance(k, t, time.monotonic() if now is None else now)

    def run_event(self, state: str, n_steps: int | None = None, h: float | None = None,
                  reason: str = "") -> None:
        with self._lock:
            self.n_steps = self.n_steps if n_steps is None else int(n_steps)
            self.h = self.h if h is None else float(h)
            if self.run_state not in ("done", "failed") or state == "failed":
                self.run_state = state
            self.reason = reason or self.reason

    def set_scenario(self, n_steps: int | None, h: float | None, nodes: list[str]) -> None:
        with self._lock:
            self.n_steps = self.n_steps if n_steps is None else int(n_steps)
            self.h = self.h if h is None else float(h)
            for n in nodes:
                self._nodes.setdefault(n, {"state": "waiting", "k": -1})

    def count_undecodable(self) -> None:
        with self._lock:
            self.undecodable += 1

    def set_fatigue(self, k: int, t: float, d: dict[str, Any]) -> None:
        with self._lock:
            self.fatigue = {"k": k, "t": t, **{n: _finite(v) for n, v in d.items()}}

    def set_coupling(self, k: int, t: float, d: dict[str, Any]) -> None:
        with self._lock:
            self._coupling.add(k, t, d)

    def set_map(self, geometry: dict[str, Any] | None, damage: dict[str, Any]) -> None:
        with self._lock:
            if geometry is not None:
                self.map_geometry = geometry
            self.damage_map = damage

    def _node(self, node: str, state: str, k: int = -1, info: str = "") -> None:
        n = self._nodes.setdefault(node, {"state": "waiting", "k": -1})
        old = n["state"]
        if state == "gone" and old == "done":
            return
        if state in ("up", "ready", "stepping") and old in ("done", "error", "gone") and \
                not (state == "up" and old == "gone"):
            return  # a late message of a node that has ended
        if state == "up" and old not in ("waiting", "gone"):
            return
        n["state"], n["k"] = state, max(n["k"], k)
        if info:
            n["info"] = info

    def _advance(self, k: int, t: float, now: float) -> None:
        if k > self.k:
            self.k, self.t = k, t
            self._rate.append((now, k))
        if self.run_state == "waiting":
            self.run_state = "stepping"
        while len(self._rate) > 2 and now - self._rate[0][0] > RATE_WINDOW_S:
            self._rate.popleft()

    def _steps_per_s(self, now: float) -> float:
        if len(self._rate) < 2:
            return 0.0
        (t0, k0), (t1, k1) = self._rate[0], self._rate[-1]
        if self.run_state in ("stepping", "waiting") and now - t1 > RATE_WINDOW_S:
            return 0.0  # nothing came for a while
        return (k1 - k0) / (t1 - t0) if t1 > t0 else 0.0

    def nodes_known(self) -> list[str]:
        with self._lock:
            return list(self._nodes)

    def meta(self) -> dict[str, Any]:
        with self._lock:
            return {"run": self.run_id, "source": self.source, "n_steps": self.n_steps,
                    "h": self.h, "patterns": [p.text for p in self.selection.patterns],
                    "lines": [vars(s.line) for s in self._lines.values()],
                    "map_geometry": self.map_geometry}

    def snapshot(self, since: int = -1, now: float | None = None,
                 coupling_since: int = -1) -> dict[str, Any]:
        """The ``/data?since=K&coupling_since=C`` answer (steps k > K, messages k > C)."""
        now = time.monotonic() if now is None else now
        with self._lock:
            n = self.n_steps
            out: dict[str, Any] = {
                "run": self.run_id, "source": self.source, "since": since,
                "k": self.k, "t": self.t, "n_steps": n, "h": self.h,
                "progress": (max(0, self.k) / n if n else None),
                "steps_per_s": self._steps_per_s(now), "run_state": self.run_state,
                "reason": self.reason, "messages": self.messages, "undecodable": self.undecodable,
                "nodes": {name: dict(v) for name, v in sorted(self._nodes.items())},
                "lines": {key: {**vars(s.line), **s.since(since)}
                          for key, s in self._lines.items()},
                "fatigue": dict(self.fatigue) if self.fatigue else None,
                "coupling": self._coupling.since(coupling_since),
            }
            dm = self.damage_map  # its per-node damage (the big part) only if newer than K
            if dm is not None and dm["k"] <= since:
                dm = {n: v for n, v in dm.items() if n != "log10_damage"}
            out["damage_map"] = dm
            out["map_geometry"] = self.map_geometry if since < 0 else None
            return out


class _Coupling:
    """``recorder/coupling`` per message: ``k``, ``t`` [s], relative residuals [-], totals [J]."""

    def __init__(self, max_samples: int) -> None:
        self.max = max_samples
        self.k: list[int] = []
        self.t: list[float] = []
        self.rel: dict[str, list[float | None]] = {}
        self.last: dict[str, Any] | None = None
        self.steps = 0  # steps whose dE came
        self.from_k: int | None = None

    def add(self, k: int, t: float, d: dict[str, Any]) -> None:
        if self.k and k <= self.k[-1]:
            return  # a repeat
        bonds = sorted(f[4:] for f in d if f.startswith("rel_"))
        if not bonds:
            return
        for b in bonds:
            if b not in self.rel:
                self.rel[b] = [None] * len(self.k)
        self.k.append(int(k))
        self.t.append(float(t))
        for b, ys in self.rel.items():
            v = d.get(f"rel_{b}")
            ys.append(float(v) if isinstance(v, int | float) and math.isfinite(v) else None)
        n = next((len(v) for f, v in d.items() if f.startswith("dE_") and isinstance(v, list)), 0)
        self.steps += n
        if self.from_k is None and isinstance(d.get("k0"), int):
            self.from_k = d["k0"]
        self.last = {"k": int(k), "t": float(t), **{f: _finite(v) for f, v in d.items()
                                                     if not isinstance(v, list)}}
        if len(self.k) > 2 * self.max:
            del self.k[:-self.max], self.t[:-self.max]
            for ys in self.rel.values():
                del ys[:-self.max]

    def since(self, k: int) -> dict[str, Any] | None:
        if self.last is None:
            return None
        i = max(bisect_right(self.k, k), len(self.k) - self.max)
        return {"k": self.k[i:], "t": self.t[i:],
                "rel": {b: ys[i:] for b, ys in self.rel.items()},
                "threshold": self.last.get("threshold"), "last": dict(self.last),
                "steps": self.steps, "from_k": self.from_k}


def _finite(v: Any) -> Any:
    if isinstance(v, float) and not math.isfinite(v):
        return "inf" if v > 0 else "nan"
    return v
