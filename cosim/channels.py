"""The data channels of a run and their fields (SI units). Schema version: see cosim.wire.

The fields, units and bounds are declared once, in :mod:`cosim.schema`; the table below is
their description (docs/cosim.md has the table generated from the schema), and the field
tuples of this module are derived from it.

Per-corner fields are a number for a quarter car and a list of 4 (FL, FR, RL, RR) for a full
vehicle. Every channel carries one message per communication step k = 0..N (N = t_end / h).

====================  ===========  ==========================================================
channel               field        meaning
====================  ===========  ==========================================================
plant/state           z_b, z_w     body (at the corner) and wheel displacement from static
                                   equilibrium [m], at t_k
                      v_b, v_w     their velocities [m/s]
                      (full veh.)  heave [m], pitch, roll [rad], v_heave [m/s], w_pitch,
                                   w_roll [rad/s]
plant/response        a_b, a_w     accelerations at t_k [m/s^2], from PyBullet's forward
                                   dynamics under the forces of step k
                      F_t, F_d     the tyre and damper forces the plant applied at t_k [N]
                      F_s          suspension spring force on the body, dynamic part [N]
                      F_bs         jounce-bumper (bump-stop) force, compression-positive,
                                   >= 0 [N]: up on the body, down on the lower arm's pad
                                   (double-wishbone corner only; nodes/plant/bump_stop.py)
                      a_arm_<pt>_  acceleration of a point of the lower arm (pt = loc1: 20
                      <ax>         mm inboard of the ball joint, cg: its centre of mass,
                                   loc2: 20 mm outboard of the bush midpoint; thesis Table
                                   5.4), ax = x/y/z vehicle axes, at t_k [m/s^2], as a_b;
                                   kinematic (0 at rest) (double-wishbone corner only;
                                   ARM_ACCEL_POINTS in nodes/plant/double_wishbone.py)
                      alpha_pitch, body pitch (about +y, nose down +) and roll (about +x,
                      alpha_roll   left up +) accelerations at t_k [rad/s^2], as a_b
                                   (7-DOF full vehicle only)
plant/arm             <pt>_<ax>    load ON the lower arm at point pt (ball_joint,
                                   damper_mount, bush_front, bush_rear: x/y/z), axis of the
                                   arm frame at t_k (cosim/lower_arm.py) [N] (realistic
                                   models only)
                      bump_stop_y, the bumper's force on the arm at its pad, arm-frame y/z
                      bump_stop_z  [N]: -F_bs sin(theta), -F_bs cos(theta) (z <= 0; no x)
                      torsion_bar_ the torsion-bar moment on the arm about its x axis, static
                      mx           preload included [N m]; it enters the arm through its
                                   pivot, half at each bush eye (cosim/lower_arm.py)
plant/upper_arm       upper_<pt>_  load ON the upper arm at pt (ball_joint, bush_front,
                      <ax>         bush_rear: the corner file's upper_* points), axis of the
                                   upper-arm frame at t_k (origin the upper bushes' midpoint,
                                   x rear -> front bush, y toward the upper ball joint normal
                                   to x, z = x cross y; nodes/plant/upper_arm_loads.py) [N]
                                   (the double-wishbone quarter car)
plant/arm_<C>         (as arm)     C = FL, FR, RL, RR: each lower arm of the four-corner
                                   vehicle (a right arm in its mirrored frame); plant/arm is
                                   then the FL arm's
tyre_road/force       F_t          tyre force, compressive-positive, >= 0, absolute [N]
                      k_t          dF_t/d(z_g - z_w), 0 when lifted off [N/m] (for coupling)
                      z_g          road height under the wheel [m]
controller/force      F_d          damper force on the body, upward positive [N]
                      c_eff        dF_d/d(v_w - v_b) [N s/m] (for coupling)
                      (law extras) e.g. I [A] MR current, state (1 hard / 0 soft)
====================  ===========  ==========================================================

Block channels (not one message per step; published only when the fatigue node is in the run,
and not recorded in the table: they repeat or summarise recorded data):

====================  ===========  ==========================================================
recorder/loads        k0, k        a block of steps k0..k of the load channel (``plant/arm``)
                                   in step order, no gaps; ``k`` of the message = last step
                      t            (n,) times of the steps [s]
                      <pt>_<ax>    (n,) each field of ``plant/arm`` [N]
fatigue/damage        max_damage   largest Miner damage of any node for the history so far,
                                   residue closed as at the end of a run [-]
                      critical_node_id, distance_m (road covered so far [m]),
                      life_km      projected minimum life: distance_m / max_damage / 1000
recorder/coupling     k0           first step of the message's dE lists; ``k`` of the
                                   message = last step k0 + n - 1, ``t`` its time [s]
                      dE_damper,   (n,) the coupling energy residual of each step k0..k,
                      dE_tyre      per power bond, summed over corners [J]
                                   (cosim/coupling_energy.py; one message per batch of
                                   table rows: cosim.coupling_stream.LiveResidual)
                      res_<bond>,  running sum |dE| and energy the bond carried, sum h |F v|,
                      carried_<b>  over the steps so far [J]
                      rel_<bond>,  running relative residual res / carried [-]; ``total``:
                      rel_total    all bonds' as ``summary.json``'s coupling_energy_residual
                      threshold    the warning threshold of rel_total [-] (0.003)
====================  ===========  ==========================================================

``recorder/coupling`` is published in every run whose table has a power bond (not only with
the fatigue node); like the others it is not journaled nor in the table: it is computed from
the table's own rows.
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
    """``NODES`` (the nodes of every run, in start order), ``COUPLED`` (the nodes of the
    lock-step exchange; the recorder and the fatigue worker only listen) and
    ``OPTIONAL_NODES`` (nodes a run may add: the live fatigue worker), from the node
    registry (:mod:`cosim.node_kinds`, imported here when first asked: it imports this
    module)."""
    from . import node_kinds as nk

    roles = {"NODES": (nk.COUPLED, nk.LISTENER), "COUPLED": (nk.COUPLED,),
             "OPTIONAL_NODES": (nk.OPTIONAL,)}
    if name not in roles:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = nk.names(*roles[name])
    globals()[name] = value
    return value

LOAD_CHANNEL = (PLANT, ARM)
UPPER_ARM = "upper_arm"
"""The upper arm's load channel ``plant/upper_arm`` (the double-wishbone quarter car)."""
"""The channel the recorder streams to the fatigue node in blocks."""

CORNERS = ("FL", "FR", "RL", "RR")
"""The corners of a full vehicle, in the order of every per-corner list field (front left,
front right, rear left, rear right); a quarter car is the front-left corner."""
CORNER_ARMS = tuple(f"{ARM}_{c}" for c in CORNERS)
"""The four-corner vehicle's per-corner lower-arm channels ``plant/arm_FL`` .. ``arm_RR``
(the ``plant/arm`` fields, each arm in its own frame: a right arm's mirrored; ``plant/arm``
is then the front-left's)."""
STATE_FIELDS = _schema.required(PLANT, STATE)  # z_b, v_b, z_w, v_w
TYRE_FIELDS = tuple(f.name for f in _schema.BY_NAME["tyre_road/force"].fields)  # F_t, k_t, z_g
DAMPER_FIELDS = _schema.coupling(CONTROLLER)  # F_d, c_eff
