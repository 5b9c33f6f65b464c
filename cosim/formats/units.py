"""SI units of the columns of a run's table (``<node>/<channel>/<field>``, ``[i]`` for a
corner, ``t`` [s], ``k``): what the exporters write, and factors from a file's units to SI."""

from __future__ import annotations

import re

_EXACT = {
    "t": "s", "k": "-",
    "z_b": "m", "z_w": "m", "z_g": "m", "heave": "m",
    "v_b": "m/s", "v_w": "m/s", "v_heave": "m/s",
    "pitch": "rad", "roll": "rad", "w_pitch": "rad/s", "w_roll": "rad/s",
    "alpha_pitch": "rad/s^2", "alpha_roll": "rad/s^2",
    "k_t": "N/m", "c_eff": "N s/m", "I": "A", "state": "-",
}
_CORNER = re.compile(r"\[\d+\]$")


def si_unit(column: str) -> str:
    """SI unit of a table column, "" when the schema does not say.

    >>> si_unit("plant/arm/ball_joint_z"), si_unit("plant/arm/torsion_bar_mx")
    ('N', 'N m')
    >>> si_unit("plant/response/a_w[2]"), si_unit("tyre_road/force/k_t")
    ('m/s^2', 'N/m')
    """
    field = _CORNER.sub("", column).rsplit("/", 1)[-1]
    if column.startswith("plant/arm/"):
        return "N m" if field.endswith("_mx") else "N"
    if field in _EXACT:
        return _EXACT[field]
    if field.startswith("a_"):
        return "m/s^2"
    if field.startswith("F_"):
        return "N"
    return ""


_FORCE = {"n": 1.0, "kn": 1e3, "mn": 1e6, "dan": 10.0}
_MOMENT = {"nm": 1.0, "n m": 1.0, "n.m": 1.0, "n*m": 1.0, "n·m": 1.0,
           "knm": 1e3, "kn m": 1e3, "kn.m": 1e3, "kn*m": 1e3, "nmm": 1e-3, "n mm": 1e-3}
_LENGTH = {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "um": 1e-6, "µm": 1e-6}


def to_si_factor(unit: str, quantity: str) -> float | None:
    """Factor from ``unit`` to SI for ``quantity`` ("force" [N], "moment" [N m], "length"
    [m]); 1 for an empty unit; None when ``unit`` is not one of that quantity's."""
    u = unit.strip().lower()
    if not u:
        return 1.0
    table = {"force": _FORCE, "moment": _MOMENT, "length": _LENGTH}[quantity]
    return table.get(u)
