"""A measured (or exported) load file mapped onto the lower arm's load channels.

The arm's load channels are the ``plant/arm`` fields the influence coefficients answer to
(built in: :data:`influence.BUILTIN_CASES`, e.g. ``ball_joint_z`` [N], ``torsion_bar_mx``
[N m]; imported: the keys of ``fatigue.mapping``). A file channel is taken for one of them

* by name: ``plant/arm/ball_joint_z`` or ``ball_joint_z`` (what ``suscosim export`` writes), or
* by an explicit map entry ``SOURCE=TARGET`` or ``SOURCE=TARGET*SCALE`` (a rig channel
  ``LCA_BJ_Fz=ball_joint_z``; ``*-1`` flips an axis convention), which wins over a name match.

Values are converted to SI from the channel's unit (N, kN, daN, MN; N m, kN m, N mm; an
empty unit is taken as SI); any other unit is an error naming the channel. Arm channels the
file does not give get zero load (listed as missing in the result), as for a run's table.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np

from cosim.errors import InputFileError, ScenarioError
from cosim.formats import ChannelSet
from cosim.formats.units import to_si_factor

from .influence import short_channel


def parse_map(entries: Iterable[str]) -> dict[str, tuple[str, float]]:
    """``["SRC=DST", "SRC=DST*-1"]`` -> {SRC: (DST short name, scale)}."""
    out: dict[str, tuple[str, float]] = {}
    for item in entries:
        if "=" not in item:
            raise ScenarioError("--map", item, "SOURCE=TARGET or SOURCE=TARGET*SCALE")
        src, dst = (s.strip() for s in item.rsplit("=", 1))
        scale = 1.0
        if "*" in dst:
            dst, sc = (s.strip() for s in dst.split("*", 1))
            try:
                scale = float(sc)
            except ValueError:
                raise ScenarioError("--map", item, "a number after '*' (the scale)") from None
        if not src or not dst:
            raise ScenarioError("--map", item, "SOURCE=TARGET with both names given")
        out[src] = (short_channel(dst), scale)
    return out


def arm_loads(cs: ChannelSet, path: str, targets: Sequence[str],
              mapping: dict[str, tuple[str, float]] | None = None) -> dict[str, np.ndarray]:
    """``{plant/arm/<target>: values in N or N m}`` from a channel set.

    ``targets``: the arm's load channel short names; ``mapping``: :func:`parse_map`'s result.
    Raises InputFileError (naming ``path``) when a mapped channel is missing, a unit is not a
    force/moment unit, two channels land on one target, or no channel maps to any target.
    """
    mapping = dict(mapping or {})
    chosen: dict[str, tuple[str, float]] = {}  # target -> (source, scale)
    for name in cs.channels:
        short = short_channel(name)
        if short in targets and name not in mapping:
            if short in chosen:
                raise InputFileError(path, f"channels {chosen[short][0]!r} and {name!r} both "
                                           f"are the arm's {short!r}")
            chosen[short] = (name, 1.0)
    for src, (dst, scale) in mapping.items():
        if src not in cs.channels:
            raise InputFileError(path, f"mapped channel {src!r} is not in the file (it has "
                                       + ", ".join(list(cs.channels)[:12]) + ")")
        if dst not in targets:
            raise ScenarioError("--map", f"{src}={dst}",
                                "an arm load channel: " + ", ".join(targets))
        chosen[dst] = (src, scale)
    if not chosen:
        raise InputFileError(path, "no channel maps to an arm load channel; the file has "
                             + ", ".join(list(cs.channels)[:12]) + "; expected names "
                             + ", ".join(f"plant/arm/{n}" for n in targets)
                             + " or --map SOURCE=TARGET")
    out: dict[str, np.ndarray] = {}
    for dst, (src, scale) in chosen.items():
        unit = cs.units.get(src, "")
        factor = to_si_factor(unit, "moment" if dst.endswith("_mx") else "force")
        if factor is None:
            kind = "a moment (N m, kN m)" if dst.endswith("_mx") else "a force (N, kN)"
            raise InputFileError(path, f"channel {src!r} has unit {unit!r}: {kind} is "
                                       f"expected for {dst}")
        out[f"plant/arm/{dst}"] = np.asarray(cs.channels[src], dtype=float) * factor * scale
    return out
