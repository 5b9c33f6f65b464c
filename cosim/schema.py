"""The typed channel schema, declared once: every data channel's fields, units and bounds.

From :data:`CHANNELS` derive the wire codec's plausibility checks (:mod:`cosim.wire`), the
fields a consumer requires, a node's outputs, the docs' channel table (:func:`doc_table`,
docs/cosim.md; a test keeps them equal) and the table's column names.

Bounds. The thesis fixes none: they are plausibility limits far outside anything a road
vehicle's suspension produces. The channel limit is ``|x| <= 1e9`` in SI units (the Chapter 6
corner's largest stiffness, the bump stop at full compression, is below 1e6 N/m and 1e5 N);
``nonneg`` fields must be ``>= 0`` (DESIGN.md: the tyre force is compressive-positive).
Undeclared fields (a law's extras, a user's node's outputs) are type-checked only: a law's
extra may be NaN by design (TSS3's ``F_demand`` where it demands nothing). Per-corner fields
are a number for a quarter car and a list of 4 (FL, FR, RL, RR) for a full vehicle.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Annotated, Any

import msgspec

LIMIT = 1e9  # the bound of every number of a vehicle channel [SI units]
DEFAULT_LIMIT = LIMIT  # an undeclared channel's (out of it: the slow path, type-checked only)


@dataclass(frozen=True)
class Field:
    """One field of a channel; ``required`` by the consumers that couple through it;
    ``models``: who publishes it ("": all)."""

    name: str
    unit: str
    meaning: str
    nonneg: bool = False
    required: bool = False
    models: str = ""


@dataclass(frozen=True)
class Channel:
    """One data channel ``node/channel`` (key ``suscosim/<run>/<node>/<channel>``)."""

    node: str
    channel: str
    fields: tuple[Field, ...]
    meaning: str
    limit: float = LIMIT  # every number within [-limit, limit] (inf: only NaN refused)
    stepped: bool = True  # one message a step (else a block channel: not in the table)

    @property
    def name(self) -> str:
        return f"{self.node}/{self.channel}"


_PTS = ("loc1", "cg", "loc2")
_ARM_POINTS = ("ball_joint", "damper_mount", "bush_front", "bush_rear")
_UPPER_ARM_POINTS = ("upper_ball_joint", "upper_bush_front", "upper_bush_rear")
_DW = "double wishbone"
_FV = "7-DOF full vehicle"
_FVDW = "full_vehicle_double_wishbone"
_MF = "magic_formula tyre"
_ARM_CORNERS = ("FL", "FR", "RL", "RR")


def _arm_fields() -> tuple[Field, ...]:  # plant/arm and the per-corner plant/arm_<C>
    return (
        *(Field(f"{p}_{ax}", "N", f"load ON the lower arm at {p}, arm-frame {ax} axis "
                "(cosim/lower_arm.py)", models=_DW)
          for p in _ARM_POINTS for ax in "xyz"),
        Field("bump_stop_y", "N", "bumper force on the arm at its pad, arm-frame y",
              models=_DW),
        Field("bump_stop_z", "N", "bumper force on the arm at its pad, arm-frame z (<= 0)",
              models=_DW),
        Field("torsion_bar_mx", "N m", "torsion-bar moment on the arm about its x axis, "
              "preload included", models=_DW),
    )


CHANNELS: tuple[Channel, ...] = (
    Channel("plant", "state", (
        Field("z_b", "m", "body displacement at the corner from static equilibrium, at t_k",
              required=True),
        Field("v_b", "m/s", "body velocity at the corner", required=True),
        Field("z_w", "m", "wheel displacement from static equilibrium", required=True),
        Field("v_w", "m/s", "wheel velocity", required=True),
        Field("z_damper", "m", "damper compression from static", models=_DW),
        Field("v_damper", "m/s", "damper compression velocity", models=_DW),
        Field("arm_angle", "rad", "lower-arm angle from static", models=_DW),
        Field("heave", "m", "body heave", models=_FV),
        Field("pitch", "rad", "body pitch", models=_FV),
        Field("roll", "rad", "body roll", models=_FV),
        Field("v_heave", "m/s", "heave velocity", models=_FV),
        Field("w_pitch", "rad/s", "pitch rate", models=_FV),
        Field("w_roll", "rad/s", "roll rate", models=_FV),
        Field("vx_wc", "m/s", "wheel centre's velocity along the wheel's road-plane x "
              "(forward in the wheel plane)", models=_FVDW),
        Field("vy_wc", "m/s", "wheel centre's velocity along the road-plane y (left)",
              models=_FVDW),
        Field("omega_w", "rad/s", "wheel spin rate, forward rolling positive", models=_FVDW),
        Field("gamma", "rad", "inclination of the wheel plane to the road normal, top to +y "
              "positive (ISO-W)", models=_FVDW),
        Field("x_wc", "m", "wheel centre's world x (its place along the road)",
              models=_FVDW),
        Field("y_wc", "m", "wheel centre's world y", models=_FVDW),
        Field("r_l", "m", "loaded radius: contact point below the centre, rolling radius",
              nonneg=True, models=_FVDW),
        Field("x", "m", "body CG's world x", models=_FVDW),
        Field("y", "m", "body CG's world y", models=_FVDW),
        Field("yaw", "rad", "body heading", models=_FVDW),
        Field("u", "m/s", "CG's speed along the heading", models=_FVDW),
        Field("v", "m/s", "CG's speed across the heading (left)", models=_FVDW),
        Field("w_yaw", "rad/s", "yaw rate", models=_FVDW),
    ), "the plant's state at t_k (what the force nodes compute step k's forces from)"),
    Channel("plant", "response", (
        Field("a_b", "m/s^2", "body acceleration at t_k under the forces of step k"),
        Field("a_w", "m/s^2", "wheel acceleration at t_k"),
        Field("F_t", "N", "tyre force the plant applied at t_k"),
        Field("F_d", "N", "damper force the plant applied at t_k"),
        Field("F_s", "N", "suspension spring force on the body, dynamic part"),
        Field("F_bs", "N", "jounce-bumper force, compression-positive", nonneg=True,
              models=_DW),
        *(Field(f"a_arm_{p}_{ax}", "m/s^2", f"acceleration of arm point {p} along {ax} "
                "(thesis Table 5.4; kinematic, 0 at rest)", models=_DW)
          for p in _PTS for ax in "xyz"),
        Field("alpha_pitch", "rad/s^2", "body pitch acceleration", models=_FV),
        Field("alpha_roll", "rad/s^2", "body roll acceleration", models=_FV),
    ), "the plant's response of step k (published with the state of step k + 1)"),
    Channel("plant", "arm", _arm_fields(),
            "the component loads of step k (realistic models only; the four-corner vehicle: "
            "the front-left arm's, as arm_FL)"),
    Channel("plant", "upper_arm", tuple(
        Field(f"{p}_{ax}", "N", f"load ON the upper arm at {p}, upper-arm-frame {ax} axis",
              models=_DW)
        for p in _UPPER_ARM_POINTS for ax in "xyz"),
            "the upper arm's loads of step k (the double-wishbone quarter car); upper-arm "
            "frame: origin the upper bushes' midpoint, x rear -> front bush, y toward the "
            "upper ball joint normal to x, z = x cross y, turning with the arm "
            "(nodes/plant/upper_arm_loads.py)"),
    *(Channel("plant", f"arm_{c}", _arm_fields(),
              f"the {c} lower arm's loads of step k (four-corner vehicle; a right arm in its "
              "mirrored frame, docs/corners.md)") for c in _ARM_CORNERS),
    Channel("tyre_road", "force", (
        Field("F_t", "N", "tyre force, compressive-positive, absolute", nonneg=True,
              required=True),
        Field("k_t", "N/m", "dF_t/d(z_g - z_w), 0 when lifted off (for coupling)",
              nonneg=True, required=True),
        Field("z_g", "m", "road height under the wheel's contact centre"),
        Field("Fx", "N", "tyre force along the wheel's road-plane x (forward), at the contact "
              "point", models=_MF),
        Field("Fy", "N", "tyre force along the road-plane y (left)", models=_MF),
        Field("Mz", "N m", "aligning moment about the road normal", models=_MF),
        Field("kappa", "-", "longitudinal slip that acts (after the relaxation)", models=_MF),
        Field("alpha", "rad", "slip angle that acts (ISO-W)", models=_MF),
    ), "the tyre force of step k"),
    Channel("controller", "force", (
        Field("F_d", "N", "damper force on the body, upward positive", required=True),
        Field("c_eff", "N s/m", "dF_d/d(v_w - v_b) (for coupling)", required=True),
        Field("I", "A", "MR damper current (MR laws)"),
        Field("state", "-", "switching state, 1 hard / 0 soft (two-state laws)"),
    ), "the damper force of step k, and the law's extras"),
    Channel("recorder", "loads", (
        Field("k0", "-", "first step of the block", nonneg=True, required=True),
        Field("t", "s", "(n,) times of the steps", nonneg=True, required=True),
    ), "a block of steps k0..k of plant/arm in step order (each plant/arm field as an (n,) "
       "list); only with a live fatigue node", stepped=False),
    Channel("recorder", "coupling", (
        Field("k0", "-", "first step of the dE lists (the message's k is the last)",
              nonneg=True, required=True),
        Field("dE_damper", "J", "(n,) coupling energy residual of each step, damper bond"),
        Field("dE_tyre", "J", "(n,) coupling energy residual of each step, tyre bond"),
        Field("res_damper", "J", "running sum of abs(dE) of the damper bond", nonneg=True),
        Field("res_tyre", "J", "running sum of abs(dE) of the tyre bond", nonneg=True),
        Field("carried_damper", "J", "running energy the damper bond carried", nonneg=True),
        Field("carried_tyre", "J", "running energy the tyre bond carried", nonneg=True),
        Field("rel_damper", "-", "running relative residual, damper bond", nonneg=True),
        Field("rel_tyre", "-", "running relative residual, tyre bond", nonneg=True),
        Field("rel_total", "-", "running relative residual, all bonds", nonneg=True),
        Field("threshold", "-", "the warning threshold of rel_total", nonneg=True),
    ), "the live coupling energy residual, per batch of table rows (docs/"
       "coupling_residual.md)", limit=math.inf, stepped=False),
    Channel("fatigue", "damage", (
        Field("max_damage", "-", "largest Miner damage of any node so far", nonneg=True),
        Field("critical_node_id", "-", "the node of it"),
        Field("distance_m", "m", "road covered so far", nonneg=True),
        Field("life_km", "km", "projected minimum life (inf: no damage yet)", nonneg=True),
    ), "the live fatigue node's damage so far", limit=math.inf, stepped=False),
)
"""Every declared data channel (see the module's docstring)."""

BY_NAME: dict[str, Channel] = {c.name: c for c in CHANNELS}


def channel(node: str, name: str) -> Channel | None:
    return BY_NAME.get(f"{node}/{name}")


def required(node: str, name: str) -> tuple[str, ...]:
    """The fields a message of ``node/name`` must have."""
    c = channel(node, name)
    return tuple(f.name for f in c.fields if f.required) if c else ()


def coupling(node: str) -> tuple[str, ...]:
    """The coupling fields of ``node``'s ``force``."""
    return required(node, "force")


def writes(node: str) -> tuple[str, ...]:
    """The declared data channels ``node`` publishes, in declaration order."""
    return tuple(c.channel for c in CHANNELS if c.node == node)


def columns(node: str, name: str, fields: Iterable[str] | None = None) -> list[str]:
    """The table's columns ``node/name/field`` (the declared fields, or ``fields``)."""
    c = channel(node, name)
    names = list(fields) if fields is not None else [f.name for f in c.fields] if c else []
    return [f"{node}/{name}/{f}" for f in names]


def doc_table() -> str:
    """The channel table of docs/cosim.md (markdown), from :data:`CHANNELS`."""
    rows = ["| channel | field | unit | bound | meaning |", "|---|---|---|---|---|"]
    for c in CHANNELS:
        lim = "finite" if c.limit == math.inf else f"abs <= {c.limit:.0e}"
        rows.append(f"| `{c.name}` | | | {lim} | {c.meaning} |")
        for f in c.fields:
            bound = ">= 0" if f.nonneg else ""
            extra = (" (required)" if f.required else "") + (f" ({f.models})" if f.models else "")
            rows.append(f"| | `{f.name}` | {f.unit} | {bound} | {f.meaning}{extra} |")
    return "\n".join(rows)


# ---- the compiled decoders ------------------------------------------------------------------
def _number(limit: float) -> Any:
    """int | float within [-limit, limit] (NaN fails any bound); a bool is not a number."""
    if limit == math.inf:  # msgspec bounds are finite: NaN is refused by the codec's check
        return int | float
    return Annotated[int, msgspec.Meta(ge=-int(limit), le=int(limit))] | \
        Annotated[float, msgspec.Meta(ge=-limit, le=limit)]


def payload_type(limit: float) -> Any:
    """The type of a data payload: field -> a bounded number or a non-empty list of them."""
    num = _number(limit)
    return dict[str, num | Annotated[list[num], msgspec.Meta(min_length=1)]]  # type: ignore


def nonneg_fields(node: str, name: str) -> tuple[str, ...]:
    c = channel(node, name)
    return tuple(f.name for f in c.fields if f.nonneg) if c else ()


def negative(d: dict[str, Any], names: tuple[str, ...]) -> str | None:
    """The first of ``names`` in ``d`` with a value < 0 (None: none)."""
    for f in names:
        v = d.get(f)
        if v is None:
            continue
        if (min(v) if type(v) is list else v) < 0:
            return f
    return None
