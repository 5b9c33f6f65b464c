"""More than one part in a run (``[fatigue] parts``, docs/parts.md "A second part: the upper
wishbone"): which plant load channel each part takes, and the names its load columns go by.

A part's load channel is the declared plant channel whose fields its load cases name: the
upper arm's (``plant/upper_arm``, fields ``upper_ball_joint_x`` ...) if any case is one of
them, else the primary arm channel (``plant/arm``, or ``plant/arm_<corner>``). Each part is
analysed with the run's fatigue settings (its own influence coefficients) and written to
``fatigue/<part name>/`` beside the primary part's files in ``fatigue/``.

Column names: the lower arm's loads go by their table names (``plant/arm/ball_joint_z``); any
other channel's by the names the part's cases use (the bare field, ``upper_ball_joint_z``, as
the shipped part names them, or the full ``plant/upper_arm/upper_ball_joint_z``), so that
the worker's case matching (:func:`.influence.short_channel`, which strips ``plant/arm/``
only) pairs them.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, replace
from pathlib import Path

from cosim import schema

from .config import FatigueConfig

UPPER_ARM = "upper_arm"
"""The upper arm's load channel (``plant/upper_arm``)."""
NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_-]*$")
"""A part name usable as the folder ``fatigue/<name>/``."""


def _fields(channel: str) -> tuple[str, ...]:
    c = schema.channel("plant", channel)
    return tuple(f.name for f in c.fields) if c is not None else ()


def channel_of_cases(cases: list[str], default: str) -> str:
    """The plant load channel whose fields ``cases`` name (module docstring)."""
    upper = _fields(UPPER_ARM)
    for c in cases:
        name = c[len(f"plant/{UPPER_ARM}/"):] if c.startswith(f"plant/{UPPER_ARM}/") else c
        if name in upper:
            return UPPER_ARM
    return default


def part_channels(cfg: FatigueConfig) -> list[str]:
    """The load channels a config's part file names (empty: not a part file)."""
    if cfg.influence.lower().endswith(".toml"):
        from .parts import load_part

        return load_part(cfg.influence_path).channels
    return []


def load_channel(cfg: FatigueConfig) -> str:
    """The plant channel of ``cfg``'s part (``arm``, ``arm_<corner>`` or ``upper_arm``)."""
    return channel_of_cases(part_channels(cfg), cfg.load_channel)


def column_names(channel: str, fields: list[str], cases: list[str]) -> list[str]:
    """The names the load columns of ``channel``'s ``fields`` go by (module docstring; any
    channel but the upper arm's, a corner's too, is the lower arm's ``plant/arm/...``)."""
    if channel != UPPER_ARM:
        return [f"plant/arm/{f}" for f in fields]
    return [f"plant/{channel}/{f}" if f"plant/{channel}/{f}" in cases else f for f in fields]


@dataclass(frozen=True)
class MorePart:
    """One of ``[fatigue] parts``: its name (results folder), settings and load channel."""

    name: str
    cfg: FatigueConfig
    channel: str

    @property
    def cases(self) -> list[str]:
        return part_channels(self.cfg)


def primary_name(cfg: FatigueConfig) -> str:
    """The primary part's name: its part file's, ``lower_arm`` for the built-in arm, else
    the imported folder's name."""
    if cfg.influence.startswith("builtin"):
        return "lower_arm"
    if cfg.influence.lower().endswith(".toml"):
        from .parts import load_part

        return load_part(cfg.influence_path).name
    return Path(cfg.influence).name


def more_parts(cfg: FatigueConfig) -> list[MorePart]:
    """``cfg.parts`` as :class:`MorePart` (each: ``cfg`` with its part file as the influence
    and no more parts); a name that is no folder name, repeats another's or the primary's
    is a ScenarioError naming ``fatigue.parts``."""
    from cosim.errors import ScenarioError

    from .parts import load_part

    out: list[MorePart] = []
    names = {primary_name(cfg)} if cfg.parts else set()
    for path in cfg.parts:
        part = load_part(path)
        if not NAME.match(part.name):
            raise ScenarioError("fatigue.parts", path, f"a part whose name ({part.name!r}) is "
                                "a folder name (letters, digits, _ and -)")
        if part.name in names:
            raise ScenarioError("fatigue.parts", list(cfg.parts), f"parts of distinct names "
                                f"({part.name!r} twice, or the primary part's)")
        names.add(part.name)
        sub = replace(cfg, influence=path, mapping=(), parts=())
        out.append(MorePart(part.name, sub, channel_of_cases(part.channels,
                                                             cfg.load_channel)))
    return out
