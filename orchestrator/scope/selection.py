"""Which signals the scope plots: ``--channels`` patterns ``NODE/CHANNEL[/FIELD]`` (names or
shell wildcards: ``plant/state``, ``*/force/F_*``), their key expressions, and the lines (SI
units) a message gives; a list field gives a line per corner. Control channels never plot.
"""

from __future__ import annotations

import fnmatch
import re
from dataclasses import dataclass

from cosim import keys
from cosim.channels import CORNERS
from cosim.errors import SuscosimError

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
