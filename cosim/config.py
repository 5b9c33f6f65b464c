"""One reader for every configuration table: typed values, checked, named by dotted key.

Every model factory reads its scenario table through a :class:`ConfigReader`, e.g.
``ConfigReader(cfg, "tyre", KEYS).number("stiffness", positive=True, unit="N/m")``. A bad
value, a missing required key or an unknown key (refused by :meth:`ConfigReader.only` or
:meth:`ConfigReader.finish`, the closest accepted key suggested) raises
:class:`cosim.errors.ScenarioError` naming the dotted key (``road.events[1].height``), the
value and what was expected (exit code 2). ``bool`` is not a number; ``inf`` / ``nan`` are
refused.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Iterable, Mapping
from typing import Any

from .errors import ScenarioError, UnknownKeyError

__all__ = ["REQUIRED", "ConfigReader", "describe_range"]


class _Required:
    def __repr__(self) -> str:
        return "REQUIRED"


REQUIRED: Any = _Required()
"""Default meaning "this key must be given" (typed ``Any`` so it fits every default)."""


def _is_number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def describe_range(lo: float | None = None, hi: float | None = None, *, lo_open: bool = False,
                   hi_open: bool = False, unit: str = "") -> str:
    """The range part of an "expected" text: ``" in [0, 0.6] A"``, ``" > 0"``, ``" (A)"``."""
    u = f" {unit}" if unit else ""
    if lo is not None and hi is not None:
        return f" in {'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}{u}"
    if lo is not None:
        return f" {'>' if lo_open else '>='} {lo:g}{u}"
    if hi is not None:
        return f" {'<' if hi_open else '<='} {hi:g}{u}"
    return f" ({unit})" if unit else ""


def _in_range(x: float, lo: float | None, hi: float | None, lo_open: bool,
              hi_open: bool) -> bool:
    if lo is not None and not (x > lo if lo_open else x >= lo):
        return False
    return hi is None or (x < hi if hi_open else x <= hi)


class ConfigReader:
    """Reads one configuration table ``name`` (dotted; ``""``: top level); ``keys``: see
    :meth:`only`. ScenarioError when ``cfg`` is not a table or has an unknown key."""

    def __init__(self, cfg: object, name: str, keys: Iterable[str] | None = None) -> None:
        if not isinstance(cfg, Mapping):
            raise ScenarioError(name, cfg, "a table")
        self.cfg: Mapping[str, Any] = cfg
        self.name = name
        self._declared: set[str] = set()
        self._read: set[str] = set()
        if keys is not None:
            self.only(keys)

    def key(self, name: str) -> str:  # "controller.c_sky"
        return f"{self.name}.{name}" if self.name else name

    def error(self, name: str, value: object, expected: str) -> ScenarioError:
        return ScenarioError(self.key(name), value, expected)

    def has(self, name: str) -> bool:
        return name in self.cfg

    def names(self) -> list[str]:
        return [str(k) for k in self.cfg]

    def _get(self, name: str, default: Any, expected: str) -> Any:
        self._read.add(name)
        if name in self.cfg:
            return self.cfg[name]
        if default is REQUIRED:
            raise self.error(name, None, f"{expected} (missing)")
        return default

    def only(self, keys: Iterable[str], *, unlisted: Iterable[str] = ()) -> None:
        """Refuse every key outside ``keys`` and ``unlisted`` (declared for :meth:`finish` too)."""
        allowed = set(keys)
        self._declared |= allowed | set(unlisted)
        for k in self.cfg:
            if k not in self._declared:
                raise self._unknown(str(k), sorted(allowed))

    def finish(self, *, also: Iterable[str] = ()) -> None:
        """Refuse every key neither read nor declared (nor in ``also``); call it last."""
        known = self._read | self._declared | set(also)
        for k in self.cfg:
            if k not in known:
                raise self._unknown(str(k), sorted(known))

    def _unknown(self, name: str, known: list[str]) -> ScenarioError:
        close = difflib.get_close_matches(name, known, n=1)
        hint = f" (did you mean '{close[0]}'?)" if close else ""
        return UnknownKeyError(self.key(name), self.cfg[name], known, hint)

    def value(self, name: str, default: Any = None) -> Any:
        """The raw value of ``name`` (``default`` when absent), unchecked."""
        return self._get(name, default, "a value")

    def number(self, name: str, default: Any = REQUIRED, *, lo: float | None = None,
               hi: float | None = None, lo_open: bool = False, hi_open: bool = False,
               positive: bool = False, unit: str = "", expected: str | None = None) -> float:
        """A finite number in [lo, hi] (open with ``lo_open``/``hi_open``; ``positive``: > 0);
        ``default`` is returned unchecked; ``unit`` and ``expected`` are for the message."""
        if positive and lo is None:
            lo, lo_open = 0.0, True
        what = expected or "a number" + describe_range(lo, hi, lo_open=lo_open,
                                                       hi_open=hi_open, unit=unit)
        value = self._get(name, default, what)
        if name not in self.cfg:
            return float(value)
        if not (_is_number(value) and math.isfinite(value)
                and _in_range(float(value), lo, hi, lo_open, hi_open)):
            raise self.error(name, value, what)
        return float(value)

    def optional_number(self, name: str, *, lo: float | None = None, hi: float | None = None,
                        lo_open: bool = False, hi_open: bool = False, positive: bool = False,
                        unit: str = "", expected: str | None = None) -> float | None:
        """:meth:`number`, or ``None`` when the key is absent."""
        if name not in self.cfg:
            self._read.add(name)
            return None
        return self.number(name, lo=lo, hi=hi, lo_open=lo_open, hi_open=hi_open,
                           positive=positive, unit=unit, expected=expected)

    def integer(self, name: str, default: Any = REQUIRED, *, lo: int | None = None,
                hi: int | None = None, expected: str | None = None) -> int:
        """An integer (a TOML integer: not ``bool``, not ``2.0``) in [lo, hi]."""
        what = expected or "an integer" + describe_range(lo, hi)
        value = self._get(name, default, what)
        if name not in self.cfg:
            return int(value)
        if (isinstance(value, bool) or not isinstance(value, int)
                or not _in_range(value, lo, hi, False, False)):
            raise self.error(name, value, what)
        return value

    def number_list(self, name: str, default: Any = REQUIRED, *, length: int | None = None,
                    expected: str | None = None) -> list[float]:
        """A list (or tuple) of finite numbers as floats, of ``length`` items if given."""
        what = expected or ("a list of " + (f"{length} " if length is not None else "")
                            + "numbers")
        value = self._get(name, default, what)
        if name not in self.cfg:
            return [float(x) for x in value]
        if not (isinstance(value, list | tuple)
                and (length is None or len(value) == length)
                and all(_is_number(x) and math.isfinite(x) for x in value)):
            raise self.error(name, value, what)
        return [float(x) for x in value]

    def choice(self, name: str, options: Iterable[str], default: Any = REQUIRED, *,
               expected: str | None = None) -> str:
        """One of the strings ``options``."""
        opts = list(options)
        what = expected or "one of " + ", ".join(repr(o) for o in opts)
        value = self._get(name, default, what)
        if name not in self.cfg:
            return str(value)
        if not isinstance(value, str) or value not in opts:
            raise self.error(name, value, what)
        return value

    def boolean(self, name: str, default: Any = REQUIRED) -> bool:
        """``true`` or ``false`` (not 0 / 1)."""
        value = self._get(name, default, "true or false")
        if name not in self.cfg:
            return bool(value)
        if not isinstance(value, bool):
            raise self.error(name, value, "true or false")
        return value

    def string(self, name: str, default: Any = REQUIRED, *, empty: bool = False,
               expected: str | None = None) -> str:
        """A string, non-empty unless ``empty``."""
        what = expected or ("a string" if empty else "a non-empty string")
        value = self._get(name, default, what)
        if name not in self.cfg:
            return str(value)
        if not isinstance(value, str) or not (value or empty):
            raise self.error(name, value, what)
        return value

    def optional_string(self, name: str, *, empty: bool = False,
                        expected: str | None = None) -> str | None:
        """:meth:`string`, or ``None`` when the key is absent."""
        if name not in self.cfg:
            self._read.add(name)
            return None
        return self.string(name, empty=empty, expected=expected)

    def table(self, name: str) -> Mapping[str, Any]:
        """The sub-table ``name`` as a raw mapping (empty when absent)."""
        value = self._get(name, {}, "a table")
        if not isinstance(value, Mapping):
            raise self.error(name, value, "a table")
        return value

    def section(self, name: str, keys: Iterable[str] | None = None, *,
                expected: str = "a table") -> ConfigReader:
        """A reader of the sub-table ``name`` (empty when absent), named ``<this>.<name>``."""
        value = self._get(name, {}, expected)
        if not isinstance(value, Mapping):
            raise self.error(name, value, expected)
        return ConfigReader(value, self.key(name), keys)

    def sections(self, name: str, *, expected: str = "a non-empty list of tables"
                 ) -> list[ConfigReader]:
        """Readers of a required, non-empty list of tables, named ``<this>.<name>[i]``."""
        value = self._get(name, REQUIRED, expected)
        if not isinstance(value, list | tuple) or not value:
            raise self.error(name, value, expected)
        return [ConfigReader(v, f"{self.key(name)}[{i}]") for i, v in enumerate(value)]
