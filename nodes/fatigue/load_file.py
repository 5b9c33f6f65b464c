"""A measured (or exported) load file mapped onto the lower arm's load channels.

The arm's load channels are the ``plant/arm`` fields the influence coefficients answer to
(a part file's channels, e.g. the built-in arm's ``ball_joint_z`` [N], ``torsion_bar_mx``
[N m]; imported: the keys of ``fatigue.mapping``). A file channel is taken for one of them

* by name: ``plant/arm/ball_joint_z`` or ``ball_joint_z`` (what ``suscosim export`` writes), or
* by an explicit map entry ``SOURCE=TARGET`` or ``SOURCE=TARGET*SCALE`` (a rig channel
  ``LCA_BJ_Fz=ball_joint_z``; ``*-1`` flips an axis convention), which wins over a name match.

Values are converted to SI from the channel's unit (N, kN, daN, MN; N m, kN m, N mm; an
empty unit is taken as SI); any other unit is an error naming the channel. Arm channels the
file does not give get zero load (listed as missing in the result), as for a run's table.

**Plausibility** (:func:`check_loads`, for load files and run tables alike): a sample that is
not finite (NaN, inf), or whose magnitude exceeds :data:`MAX_FORCE_N` (10 MN) for a force or
:data:`MAX_MOMENT_NM` (1 MN m) for a moment, is an error naming the channel, the sample index
and its time (exit 2). The bounds are not a design limit: they are far above any load a road
vehicle's suspension joint can carry (a 3 g bump on a 1.5 t car's corner is ~20 kN) and far
below where the stress superposition loses meaning in floating point (1e12 N gave a NaN
principal stress; 1e308 N overflows to inf).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np

from cosim.errors import InputFileError, ScenarioError
from cosim.formats import ChannelSet
from cosim.formats.units import to_si_factor

from .lib.influence_set import short_channel

MAX_FORCE_N = 1.0e7
"""Largest plausible force sample (N) in a load history (module docstring)."""
MAX_MOMENT_NM = 1.0e6
"""Largest plausible moment sample (N m) in a load history (module docstring)."""


def check_loads(loads: dict[str, np.ndarray], t: np.ndarray | None, path: str) -> None:
    """Raise InputFileError(path) at the first non-finite or non-physical sample of any
    channel (``plant/arm/<name>``, N or N m), naming the channel, the sample and its time."""
    if t is not None:
        bad_t = np.flatnonzero(~np.isfinite(np.asarray(t, dtype=float)))
        if bad_t.size:
            raise InputFileError(path, f"time sample {int(bad_t[0])} is {t[bad_t[0]]!r}: "
                                       "times must be finite")
    for name, v in loads.items():
        v = np.asarray(v, dtype=float)
        bad = bad_samples(name, v)
        if bad.size:
            i = int(bad[0])
            when = None if t is None or i >= len(t) else float(t[i])
            raise InputFileError(path, bad_sample(name, i, v[i], when, bad.size))


def bad_samples(name: str, v: np.ndarray) -> np.ndarray:
    """Indices of channel ``name``'s samples ``v`` that are not finite or not plausible."""
    limit = MAX_MOMENT_NM if short_channel(name).endswith("_mx") else MAX_FORCE_N
    return np.flatnonzero(~np.isfinite(v) | (np.abs(v) > limit))


def bad_sample(name: str, i: int, x: float, t: float | None, n_bad: int) -> str:
    """What is wrong with channel ``name``'s sample ``i`` (value ``x``, at time ``t`` [s])."""
    moment = short_channel(name).endswith("_mx")
    what = "not finite" if not np.isfinite(x) else \
        f"beyond the plausible {MAX_MOMENT_NM if moment else MAX_FORCE_N:.0e} " \
        f"{'N m' if moment else 'N'}"
    when = "" if t is None else f" (t = {t:.6g} s)"
    return f"channel {name!r} sample {i}{when} is {x!r}: {what}; {n_bad} such sample(s) in " \
           "the channel"


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
        with np.errstate(over="ignore", invalid="ignore"):
            out[f"plant/arm/{dst}"] = np.asarray(cs.channels[src], dtype=float) * factor * scale
    check_loads(out, np.asarray(cs.t, dtype=float), path)
    return out
