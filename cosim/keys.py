"""Key expressions: every key is ``suscosim/<run>/<node>/<channel>``.

So runs on one network never mix: a node only ever subscribes under its own run id.
Control traffic uses the same scheme: ``<node>/ctl`` (ready, progress, done, error from a
node), ``orchestrator/clock`` (start, abort), ``orchestrator/scenario`` (queryable),
``<node>/alive`` (liveliness token). ``<node>/records`` carries a node's data messages to the
recorder in batches (see cosim.wire).
"""

from __future__ import annotations

import re

from .errors import ScenarioError

PREFIX = "suscosim"
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$")


def check_name(what: str, name: str) -> str:
    """A run id, node or channel name: letters, digits, ``_ . -``; no key-expression syntax."""
    if not isinstance(name, str) or not _NAME.match(name):
        raise ScenarioError(what, name, "1-64 letters, digits, '_', '.', '-' (no '/', '*', '$')")
    return name


def key(run: str, node: str, channel: str) -> str:
    """The key of one channel of one node of one run."""
    return f"{PREFIX}/{run}/{node}/{channel}"


def run_keyexpr(run: str) -> str:
    """Every key of a run."""
    return f"{PREFIX}/{run}/**"


def parse_key(k: str) -> tuple[str, str, str]:
    """``suscosim/<run>/<node>/<channel>`` -> (run, node, channel)."""
    parts = str(k).split("/")
    if len(parts) != 4 or parts[0] != PREFIX:
        raise ValueError(f"not a suscosim key: {k!r}")
    return parts[1], parts[2], parts[3]


CTL = "ctl"
CLOCK = "clock"
SCENARIO = "scenario"
ALIVE = "alive"
RECORDS = "records"
ORCHESTRATOR = "orchestrator"
