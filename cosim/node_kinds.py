"""The node registry: every kind of node a run can have, declared once.

A :class:`NodeKind` gives a node's name (also its key segment, log file and certificate
name), implementation, role, channels, preflight check, path keys and core; ``suscosim
node``, the run's node list and preflight, CPU placement and the deploy files derive from it
(adding a kind: docs/nodes.md). Entries are ``package.module:attribute`` strings, imported
when used (:func:`load`). A scenario picks an implementation per kind in ``[nodes]``: a named
alternative (``controller = "fmu"``) or a user's ``"package.module:Class"`` /
``"...:function"``; a bad value is a :class:`ScenarioError` naming ``nodes.<kind>``.
"""

from __future__ import annotations

import importlib
import os
import sys
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from . import schema
from .errors import ScenarioError

COUPLED, LISTENER, OPTIONAL = "coupled", "listener", "optional"
"""Roles. *coupled*: in the lock-step exchange; *listener*: in every run, takes inputs as they
come (the recorder); *optional*: a listener that joins when its check says so (fatigue)."""
ROLES = (COUPLED, LISTENER, OPTIONAL)
NATIVE = "native"  # a kind's own implementation ([nodes] controller = "native")
SECTION = "nodes"


@dataclass(frozen=True)
class Check:
    """A preflight check ``entry(scenario, *facts[takes])`` (raises on bad input); ``gives``:
    the fact its result is (None: a mapping of facts, merged). An *optional* kind's check
    returns whether it joins the run."""

    entry: str
    takes: tuple[str, ...] = ()
    gives: str | None = None


@dataclass(frozen=True)
class Impl:
    """One implementation of a kind: ``entry`` ``package.module:function`` (called as
    ``function(part, scenario)``) or ``package.module:Class`` (:mod:`cosim.stepped`)."""

    entry: str
    check: Check | None = None


@dataclass(frozen=True)
class NodeKind:
    """One kind of node (see the module's docstring)."""

    name: str
    role: str
    impl: Impl
    reads: tuple[tuple[str, str], ...] = ()  # (node, channel); node "*": every coupled writer
    writes: tuple[str, ...] = ()  # its schema channels, "step" and "records"
    provides: tuple[str, ...] = ()  # the coupling fields of its force output
    path_keys: tuple[str, ...] = ()  # dotted scenario keys holding file paths
    cores: tuple[int, int, int] = (1, 0, 3)
    """Its core with 2, 3 and >= 4 usable cores (index into the usable cores)."""
    spin_us: int = 200
    """How long a pinned node of this kind polls its input before it blocks [us]."""
    run_folder: bool = False  # writes into the run folder (its container mounts it)
    alternatives: Mapping[str, Impl] = field(default_factory=dict)  # [nodes] <name> = "<alt>"


_CONTROLLER_CHECK = Check("nodes.controller.node:static_check", takes=("n_corners",))

KINDS: tuple[NodeKind, ...] = (
    NodeKind("plant", COUPLED, Impl("nodes.plant.node:run", Check("nodes.plant.node:preflight")),
             reads=(("*", "force"),), writes=(*schema.writes("plant"), "step", "records"),
             path_keys=("vehicle.corner", "vehicle.front", "vehicle.rear"), cores=(0, 0, 0),
             spin_us=1000),  # it waits one force round trip a step: 150-300 us on 2 cores
    NodeKind("tyre_road", COUPLED,
             Impl("nodes.tyre_road.node:TyreRoad",
                  Check("nodes.tyre_road.node:static_check", gives="duration_s")),
             reads=(("plant", "state"),), writes=(*schema.writes("tyre_road"), "step", "records"),
             provides=schema.coupling("tyre_road"), path_keys=("road.path", "tyre.tir"),
             cores=(1, 1, 1), spin_us=600),  # the next state: one plant step after its force
    NodeKind("controller", COUPLED, Impl("nodes.controller.node:Controller", _CONTROLLER_CHECK),
             reads=(("plant", "state"),), writes=(*schema.writes("controller"), "step", "records"),
             provides=schema.coupling("controller"),
             path_keys=("controller.curve", "controller.fmu"),
             cores=(0, 2, 2), spin_us=600,
             alternatives={"fmu": Impl("nodes.controller.node:Controller",
                                       Check("nodes.controller.node:fmu_check",
                                             takes=("n_corners",)))}),
    NodeKind("recorder", LISTENER, Impl("nodes.recorder.node:run"),
             reads=(("*", "records"),), writes=schema.writes("recorder"), run_folder=True),
    NodeKind("fatigue", OPTIONAL,
             Impl("nodes.fatigue.node:run",
                  Check("nodes.fatigue.node:preflight", takes=("load_channels",))),
             reads=(("plant", "arm"),), writes=schema.writes("fatigue"),
             path_keys=("fatigue.influence", "fatigue.parts")),
)
"""Every node kind, in start order."""

BY_NAME: dict[str, NodeKind] = {k.name: k for k in KINDS}


def kind(name: str) -> NodeKind:
    return BY_NAME[name]


def names(*roles: str) -> tuple[str, ...]:
    """The kinds of the given roles (all, without), in start order."""
    return tuple(k.name for k in KINDS if not roles or k.role in roles)


def always() -> tuple[str, ...]:
    """The nodes of every run (coupled and listeners), in start order."""
    return names(COUPLED, LISTENER)


def producers() -> tuple[str, ...]:
    """The kinds whose data the recorder journals (their ``records`` feeds)."""
    return reads_from("recorder", "records")


def reads_from(name: str, channel: str) -> tuple[str, ...]:
    """The nodes that ``name`` reads ``channel`` from (``*`` expanded)."""
    out: list[str] = []
    for node, ch in kind(name).reads:
        if ch != channel:
            continue
        if node == "*":
            out += [k.name for k in KINDS if k.role == COUPLED and channel in k.writes
                    and k.name != name]
        else:
            out.append(node)
    return tuple(out)


def inputs(name: str) -> tuple[tuple[str, str], ...]:
    """Every (node, channel) that ``name`` reads, ``*`` expanded."""
    return tuple((node, ch) for _, ch in dict.fromkeys(kind(name).reads)
                 for node in reads_from(name, ch))


def force_sources() -> tuple[tuple[str, tuple[str, ...]], ...]:
    """(node, coupling fields) of every kind the plant takes ``force`` from."""
    return tuple((n, kind(n).provides) for n in reads_from("plant", "force"))


def path_keys() -> tuple[tuple[str, str], ...]:
    """(section, key) of every scenario key of every kind that holds a file path."""
    return tuple(tuple(p.split(".", 1)) for k in KINDS for p in k.path_keys)  # type: ignore


def core_index(name: str, n_cores: int) -> int:
    """Node ``name``'s core (index into ``n_cores`` >= 2 usable ones); no kind: a listener's."""
    cores = BY_NAME[name].cores if name in BY_NAME else NodeKind.cores
    return cores[min(n_cores, 4) - 2]


def spin_us(name: str) -> int:
    """How long node ``name`` polls its input before it blocks when pinned [us]."""
    return (BY_NAME[name] if name in BY_NAME else NodeKind).spin_us


def off_critical_path(name: str) -> bool:
    """Whether node ``name`` is off the coupled chain's critical path (not a coupled kind)."""
    return name not in BY_NAME or BY_NAME[name].role != COUPLED


# ---- implementations ----------------------------------------------------------------------
def load(entry: str, key: str = "") -> Any:
    """The object named by ``package.module:attribute``; a ScenarioError naming ``key`` (the
    scenario key it came from) when the module cannot be imported or lacks the attribute."""
    what = key or "node entry"
    module, sep, attr = entry.partition(":")
    if not sep or not module or not attr:
        raise ScenarioError(what, entry, "'package.module:Class' or 'package.module:function'")
    if os.getcwd() not in sys.path and "" not in sys.path:  # found as by python -m
        sys.path.append(os.getcwd())
    try:
        mod = importlib.import_module(module)
    except ImportError as exc:
        raise ScenarioError(what, entry, f"an importable module: cannot import '{module}' "
                            f"({type(exc).__name__}: {exc})") from None
    except Exception as exc:  # the user's module raised while being imported
        raise ScenarioError(what, entry, f"a module that imports: '{module}' raised "
                            f"{type(exc).__name__}: {exc}") from None
    obj: Any = mod
    for part in attr.split("."):
        if not hasattr(obj, part):
            raise ScenarioError(what, entry, f"an attribute of module '{module}': it has no "
                                f"'{attr}'")
        obj = getattr(obj, part)
    if not callable(obj):
        raise ScenarioError(what, entry, f"a class or function: '{attr}' is a "
                            f"{type(obj).__name__}")
    return obj


def implementation(name: str, scenario: Mapping[str, Any]) -> Impl:
    """The implementation of kind ``name`` that ``scenario``'s ``[nodes]`` picks (the kind's
    own without one); a ScenarioError naming ``nodes.<name>`` for a bad value."""
    k = kind(name)
    value = (scenario.get(SECTION) or {}).get(name, NATIVE)
    key = f"{SECTION}.{name}"
    if not isinstance(value, str):
        raise ScenarioError(key, value, _choices(k))
    if value == NATIVE:
        return k.impl
    if value in k.alternatives:
        return k.alternatives[value]
    if ":" not in value:
        raise ScenarioError(key, value, _choices(k))
    return Impl(value, None)


def _choices(k: NodeKind) -> str:
    named = ", ".join(repr(n) for n in (NATIVE, *k.alternatives))
    return f"one of {named} or 'package.module:Class' / 'package.module:function'"


def check_nodes_section(scenario: Mapping[str, Any]) -> dict[str, Impl]:
    """Kind -> implementation of every kind, ``[nodes]`` checked: every key a kind, every
    value one of its implementations, importable (user entries are imported here)."""
    section = scenario.get(SECTION)
    if section is None:
        section = {}
    if not isinstance(section, Mapping):
        raise ScenarioError(SECTION, section, "a table of node kind = implementation")
    for name in section:
        if name not in BY_NAME:
            raise ScenarioError(f"{SECTION}.{name}", section[name],
                                "a node kind: one of " + ", ".join(BY_NAME) + " (unknown kind "
                                f"'{name}')")
    out = {name: implementation(name, scenario) for name in BY_NAME}
    for name, impl in out.items():
        if impl is not kind(name).impl and impl not in kind(name).alternatives.values():
            load(impl.entry, f"{SECTION}.{name}")  # importable, the attribute exists
    return out


def user_check(impl: Impl, key: str) -> Any:
    """A user's implementation's ``preflight(scenario, facts)``, or None."""
    if impl.check is not None:
        return None
    obj = load(impl.entry, key)
    check = getattr(obj, "preflight", None)
    return check if callable(check) else None


def run_preflight(scenario: dict[str, Any]) -> tuple[list[str], dict[str, Any]]:
    """Every kind's check, in registry order, on ``scenario`` (changed in place where a check
    fills a key): the run's nodes (in start order) and the facts (``n_corners``, ...)."""
    impls = check_nodes_section(scenario)
    facts: dict[str, Any] = {}
    nodes: list[str] = []
    for k in KINDS:
        impl = impls[k.name]
        result: Any = None
        if impl.check is not None:
            fn = load(impl.check.entry, f"{SECTION}.{k.name} (its check)")
            lacking = [t for t in impl.check.takes if t not in facts]
            if lacking:  # e.g. a user's plant without a preflight giving n_corners
                raise ScenarioError(SECTION, dict(scenario.get(SECTION) or {}),
                                    f"implementations whose preflight gives "
                                    f"{', '.join(lacking)} (the check of {k.name} takes it)")
            result = fn(scenario, *(facts[t] for t in impl.check.takes))
            if impl.check.gives is not None:
                facts[impl.check.gives] = result
                result = None
        else:
            fn = user_check(impl, f"{SECTION}.{k.name}")
            if fn is not None:
                result = fn(scenario, facts)
        if k.role == OPTIONAL:
            if result:
                nodes.append(k.name)
            continue
        if isinstance(result, Mapping):
            facts.update(result)
        nodes.append(k.name)
    return nodes, facts


def entries(names_: Iterable[str] | None = None) -> dict[str, str]:
    """Kind -> the module of its own implementation (``package.module``)."""
    return {k.name: k.impl.entry.partition(":")[0] for k in KINDS
            if names_ is None or k.name in names_}
