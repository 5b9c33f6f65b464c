"""The names of a run's nodes and channels (fields, units and bounds: :mod:`cosim.schema`).

A stepped channel carries one message per communication step k = 0..N (N = t_end / h); the
block channels (``recorder/loads``, ``recorder/coupling``, ``fatigue/damage``) are neither in
the table nor journaled: they repeat or summarise recorded data.
"""

from __future__ import annotations

from . import schema as _schema

PLANT, TYRE_ROAD, CONTROLLER, RECORDER = "plant", "tyre_road", "controller", "recorder"
STATE, RESPONSE, ARM, FORCE = "state", "response", "arm", "force"
FATIGUE, LOADS, DAMAGE = "fatigue", "loads", "damage"
COUPLING = "coupling"
COUPLING_CHANNEL = (RECORDER, COUPLING)
"""The live coupling residual, per batch of table rows (docs/coupling_residual.md)."""


def __getattr__(name: str) -> tuple[str, ...]:
    """``NODES`` (in start order), ``COUPLED`` and ``OPTIONAL_NODES`` from
    :mod:`cosim.node_kinds` (imported when first asked: it imports this module)."""
    from . import node_kinds as nk

    roles = {"NODES": (nk.COUPLED, nk.LISTENER), "COUPLED": (nk.COUPLED,),
             "OPTIONAL_NODES": (nk.OPTIONAL,)}
    if name not in roles:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = nk.names(*roles[name])
    globals()[name] = value
    return value

LOAD_CHANNEL = (PLANT, ARM)  # the fatigue node's load channel
UPPER_ARM = "upper_arm"  # plant/upper_arm (the double-wishbone quarter car)

CORNERS = ("FL", "FR", "RL", "RR")
"""The corners of a full vehicle, in the order of every per-corner list field (front left,
front right, rear left, rear right); a quarter car is the front-left corner."""
CORNER_ARMS = tuple(f"{ARM}_{c}" for c in CORNERS)  # plant/arm_FL .. arm_RR
STATE_FIELDS = _schema.required(PLANT, STATE)  # z_b, v_b, z_w, v_w
