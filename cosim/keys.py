"""Key expressions: every key is ``suscosim/<run>/<node>/<channel>`` (runs on one network
never mix). Control traffic too: ``<node>/ctl`` (ready, progress, done, error from a node),
``orchestrator/clock`` (start, abort), ``orchestrator/scenario`` (queryable), ``<node>/alive``
(liveliness token); ``<node>/records`` and ``<node>/step`` carry data messages in bundles.
"""

from __future__ import annotations

import re
import secrets

from .errors import ScenarioError

PREFIX = "suscosim"
NAME = _NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$")  # a run id, node, channel


def check_name(what: str, name: str) -> str:
    """A run id, node or channel name: letters, digits, ``_ . -``; no key-expression syntax."""
    if not isinstance(name, str) or not _NAME.match(name):
        raise ScenarioError(what, name, "1-64 letters, digits, '_', '.', '-' (no '/', '*', '$')")
    return name


MAX_NAME = 64


def invocation_token() -> str:
    """6 random hex digits for the run ids of one invocation (two people running the same
    sweep through one router never share a run id)."""
    return secrets.token_hex(3)


def unique_run_id(base: str, token: str) -> str:
    """``<base>-<token>``, ``base`` cut to make a valid run id of at most 64 characters."""
    keep = MAX_NAME - len(token) - 1
    return check_name("run id", f"{base[:keep].rstrip('-_.') or 'run'}-{token}")


def key(run: str, node: str, channel: str) -> str:
    return f"{PREFIX}/{run}/{node}/{channel}"


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
STEP = "step"  # a producer's per-step bundle of its data messages
ORCHESTRATOR = "orchestrator"
