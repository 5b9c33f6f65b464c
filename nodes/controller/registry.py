"""The law registry: a control law is one function (docs/control.md, "Adding a control law").

Decorated with :func:`control_law`, named in a scenario (``[controller] law = "my_law"``):
its parameters before the ``*`` are inputs filled by name every step (per-corner arrays
``v_b``, ``v_w``, ``v_rel`` in m/s, ``z_b``, ``z_w`` in m or any other state key; the full
vehicle's scalars :data:`~nodes.controller.base.BODY_KEYS`; ``t``, ``h`` in s, ``n``;
``memory``, a dict kept for the run), those after it settings, keys of ``[controller]``
(optional with a plain default, ranged or required with :func:`Param`; :data:`SOFT` /
:data:`HARD` take the ``preset`` defaults, ``hard >= soft`` checked; a bad key is a
ScenarioError naming it, exit 2). It returns ``(F_d, c_eff[, extras])``: the force on the
body, upward positive (N), its slope dF_d/dv_rel (N·s/m), further channels; n_corners values
or scalars. A law outside this package is named ``"package.module:function"``; one that
needs a class registers a :func:`law_builder`.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import sys
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cosim.config import ConfigReader
from cosim.errors import ScenarioError
from nodes.controller.base import Controller, ControlOutput

#: (c_soft, c_hard) in N·s/m of thesis Table 5.2 (``preset`` key).
PRESETS = {"lumped": (1500.0, 2368.0), "realistic": (3800.0, 6000.0)}

_REQUIRED = object()

Builder = Callable[[ConfigReader, int, float], Controller]


@dataclass(frozen=True)
class ParamInfo:
    """A law setting (made by :func:`Param`): ``default`` (absent: required), range ``lo``,
    ``hi`` (``lo_open``: lo excluded), ``unit`` for messages, text ``choices``, ``preset``
    ``"soft"``/``"hard"`` (default from :data:`PRESETS`)."""

    default: Any = _REQUIRED
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    unit: str = ""
    choices: tuple[str, ...] = ()
    preset: str = ""

    @property
    def required(self) -> bool:
        return self.default is _REQUIRED and not self.preset


def Param(default: Any = _REQUIRED, lo: float | None = None, hi: float | None = None,
          lo_open: bool = False, unit: str = "", choices: tuple[str, ...] = (),
          preset: str = "") -> Any:
    """A setting's :class:`ParamInfo`, as its default: ``gain: float = Param(lo=0.0)``; typed
    ``Any`` (like :func:`dataclasses.field`) so the setting keeps its own type."""
    return ParamInfo(default, lo, hi, lo_open, unit, choices, preset)


#: the damper's soft (minimum) coefficient, default from ``preset`` [lumped: 1500 N·s/m]
SOFT = Param(preset="soft", lo=0.0, unit="N·s/m")
#: the damper's hard (maximum) coefficient, default from ``preset`` [lumped: 2368 N·s/m]
HARD = Param(preset="hard", lo=0.0, unit="N·s/m")


@dataclass
class LawSpec:
    """One registered law: its name, how to build it, the keys it accepts, where it is."""

    name: str
    build: Builder
    keys: tuple[str, ...]
    doc: str
    module: str
    fn: Callable[..., Any] | None = None
    params: dict[str, ParamInfo] = field(default_factory=dict)
    inputs: tuple[str, ...] = ()


#: law name (and alias) -> spec; filled by the decorators as the modules are imported.
LAWS: dict[str, LawSpec] = {}
_discovered = False


def _register(spec: LawSpec, aliases: tuple[str, ...]) -> None:
    for name in (spec.name, *aliases):
        old = LAWS.get(name)
        if old is not None and old.module != spec.module:
            raise ValueError(f"control law '{name}' is defined twice: in {old.module} and "
                             f"{spec.module}")
        LAWS[name] = spec


def _first_line(doc: str | None) -> str:
    return (inspect.cleandoc(doc or "").splitlines() or [""])[0]


def control_law(name: str, *, aliases: tuple[str, ...] = ()) -> Callable[[Callable], Callable]:
    """Register ``fn`` as the law ``name`` (see the module docstring for the signature)."""

    def register(fn: Callable[..., Any]) -> Callable[..., Any]:
        inputs: list[str] = []
        params: dict[str, ParamInfo] = {}
        for p in inspect.signature(fn).parameters.values():
            if p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD):
                raise TypeError(f"control law '{name}': no *args/**kwargs ({p.name})")
            if p.kind == p.KEYWORD_ONLY:
                d = p.default
                params[p.name] = d if isinstance(d, ParamInfo) else ParamInfo(
                    default=_REQUIRED if d is p.empty else d)
            else:
                inputs.append(p.name)
        if {"law", "velocity", "preset"} & set(params):
            raise TypeError(f"control law '{name}': 'law', 'velocity' and 'preset' are "
                            "reserved setting names")
        keys = tuple(params) + (("preset",) if any(q.preset for q in params.values()) else ())
        spec = LawSpec(name=name, keys=keys,
                       build=lambda r, n, h: FunctionLaw(n, h, spec, read_settings(params, r)),
                       doc=_first_line(fn.__doc__), module=fn.__module__, fn=fn,
                       params=params, inputs=tuple(inputs))
        _register(spec, aliases)
        fn.__suscosim_law__ = spec  # type: ignore[attr-defined]
        return fn

    return register


def law_builder(
    name: str, keys: tuple[str, ...], *, aliases: tuple[str, ...] = ()
) -> Callable[[Builder], Builder]:
    """Register ``builder(reader, n_corners, h) -> Controller`` as the law ``name`` that
    accepts ``keys`` (besides ``law`` and ``velocity``): for laws that need a class."""

    def register(builder: Builder) -> Builder:
        _register(LawSpec(name=name, build=builder, keys=tuple(keys),
                          doc=_first_line(builder.__doc__), module=builder.__module__), aliases)
        return builder

    return register


def discover() -> None:
    """Import every module of this package (except the node itself) so that their laws are
    registered; once per process."""
    global _discovered
    if _discovered:
        return
    _discovered = True
    package = sys.modules[__package__]
    for info in pkgutil.iter_modules(package.__path__):
        if info.name != "node" and not info.name.startswith("_"):
            importlib.import_module(f"{__package__}.{info.name}")


def lookup(name: Any, key: str = "controller.law") -> LawSpec:
    """The spec of the law ``name`` (registered, or ``"package.module:function"``);
    ScenarioError if unknown, not importable or not a law."""
    discover()
    if isinstance(name, str) and name in LAWS:
        return LAWS[name]
    if not (isinstance(name, str) and ":" in name):
        raise ScenarioError(key, name, f"one of {sorted(LAWS)} or 'package.module:function'")
    module_name, _, attr = name.partition(":")
    try:
        module = importlib.import_module(module_name)
    except Exception as exc:  # any failure to import a user's module is bad input
        raise ScenarioError(key, name,
                            f"an importable module ({type(exc).__name__}: {exc})") from None
    spec = getattr(getattr(module, attr, None), "__suscosim_law__", None)
    if spec is None:
        raise ScenarioError(key, name, f"a function of {module_name} decorated with "
                            "@control_law (nodes.controller.registry)")
    return spec


def read_settings(params: Mapping[str, ParamInfo], r: ConfigReader) -> dict[str, Any]:
    """A law's settings ``params`` from the scenario table, validated, defaults filled in."""
    soft_hard = PRESETS[r.choice("preset", sorted(PRESETS), "lumped")] \
        if any(p.preset for p in params.values()) else (0.0, 0.0)
    values: dict[str, Any] = {}
    for name, p in params.items():
        if p.choices:
            values[name] = r.choice(name, p.choices, *(() if p.required else (p.default,)))
        elif isinstance(p.default, bool):
            values[name] = r.boolean(name, p.default)
        elif isinstance(p.default, str):
            values[name] = r.string(name, p.default)
        else:
            default = () if p.required else \
                (soft_hard[p.preset == "hard"] if p.preset else p.default,)
            values[name] = r.number(name, *default, lo=p.lo, hi=p.hi, lo_open=p.lo_open,
                                    unit=p.unit)
    soft = [n for n, p in params.items() if p.preset == "soft"]
    hard = [n for n, p in params.items() if p.preset == "hard"]
    if soft and hard and values[hard[0]] < values[soft[0]]:
        raise ScenarioError(r.key(hard[0]), values[hard[0]],
                            f"a number >= {soft[0]} ({values[soft[0]]:g}) N·s/m")
    return values


def soft_hard(r: ConfigReader) -> tuple[float, float]:
    """(c_soft, c_hard) in N·s/m of a builder law, read as a law function's :data:`SOFT`,
    :data:`HARD`."""
    values = read_settings({"c_soft": SOFT, "c_hard": HARD}, r)
    return values["c_soft"], values["c_hard"]


class FunctionLaw(Controller):
    """A :class:`Controller` that calls a registered law function every step."""

    def __init__(self, n_corners: int, h: float, spec: LawSpec, settings: dict[str, Any]) -> None:
        super().__init__(n_corners, h)
        assert spec.fn is not None
        self.law, self.spec, self.settings = spec.name, spec, settings
        self.memory: dict[str, Any] = {}
        self.fixed_step = "h" in spec.inputs or "memory" in spec.inputs

    def step(self, t: float, state: Mapping[str, np.ndarray]) -> ControlOutput:
        args = self.inputs(state, self.spec.inputs, t=float(t), h=self.h, n=self.n,
                           memory=self.memory)
        out = self.spec.fn(*args, **self.settings)  # type: ignore[misc]
        if not isinstance(out, tuple) or len(out) not in (2, 3):
            raise TypeError(f"control law '{self.law}' must return (F_d, c_eff) or "
                            f"(F_d, c_eff, extras), got {type(out).__name__}")
        extras = out[2] if len(out) == 3 else {}
        return ControlOutput(F_d=self._corners(out[0], "F_d"), c_eff=self._corners(out[1], "c_eff"),
                             extra={k: self._corners(v, k) for k, v in extras.items()})

    def _corners(self, value: Any, what: str) -> np.ndarray:
        arr = np.asarray(value, dtype=float)
        if arr.ndim == 0:
            return np.full(self.n, float(arr))
        if arr.shape != (self.n,):
            raise ValueError(f"control law '{self.law}' returned {what} of shape {arr.shape}, "
                             f"expected ({self.n},)")
        return arr


def describe() -> list[tuple[str, str, str, str]]:
    """(name, keys, module, first docstring line) of every registered law, sorted."""
    discover()
    rows = []
    for name, spec in sorted(LAWS.items()):
        keys = ", ".join(
            f"{k}{'' if not (p := spec.params.get(k)) or not p.required else ' (required)'}"
            for k in spec.keys)
        alias = "" if name == spec.name else f" (= {spec.name})"
        rows.append((name + alias, keys, spec.module, spec.doc))
    return rows


def main(argv: list[str] | None = None) -> int:
    """``python3 -m nodes.controller.registry``: list the registered laws."""
    for name, keys, module, doc in describe():
        print(f"{name:<22} {module:<34} {doc}\n{'':<22} keys: {keys or '-'}")
    return 0


if __name__ == "__main__":  # run as a script: list from the package's own module
    from nodes.controller.registry import main as _main

    raise SystemExit(_main())
