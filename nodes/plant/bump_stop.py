"""Jounce bumper (bump stop) of the realistic front corner: a pure force law, no I/O.

The thesis's realistic corner had a bump stop (Table 4.1 lists a translational "bump stop"
joint; Ch. 5 sees it hit on the bump, and Table 4.5 explains the higher lateral component
levels on the pavé by it) but gives none of its numbers. This module gives ours.

**Where it acts.** A microcellular polyurethane (MCU) jounce bumper hangs from the body above
the lower arm's bump-stop pad (:data:`cosim.lower_arm.BUMP_STOP_PAD`, 0.215 m outboard of the
pivot axis, 0.73 of the ball-joint lever). Its compression is measured along the body's
vertical axis:

    delta = (z_pad - z_pad,0) - (z_bumper - z_bumper,0) - g            [m]

with z_pad the height of the pad point on the arm, z_bumper the height of the bumper's
mounting on the body (both from static ride height) and g the clearance between the bumper's
tip and the pad at static ride height. For delta <= 0 the bumper is free (F = 0). The force
F_bs = F(delta) >= 0 pushes the body up and the arm's pad down, equal and opposite, along the
body's vertical (the plant applies it, :mod:`nodes.plant.double_wishbone`).

**Characteristic** (compression-positive force F [N] of the compression delta [m]):

    F(delta) = k_0 delta / (1 - delta / s_b)                 for 0 < delta <= r s_b
    F(delta) = F(r s_b) + k_1 (delta - r s_b),  k_1 = k_0 / (1 - r)^2   beyond,

a hyperbolic progression: the rate is k_0 at first contact (the soft, thin-walled tip of the
bumper buckling), it doubles by delta = 0.29 s_b and grows without bound as the cell structure
closes towards its block compression s_b (the bumper turning into solid polyurethane). Past
r s_b (r = 0.9, where the rate is 100 k_0) the law continues along its tangent, so the force
stays finite, monotonic and C1 if a violent impact drives delta past the block (the model
integrates with a fixed step; a pole at s_b would change sign there).

**Numbers** (:class:`BumpStopParams` defaults) and why:

* *bumper*: an MCU jounce bumper of about 60 mm free length (the size fitted inside or beside
  the damper of C-segment cars and small MPVs); MCU compresses to about a third of its free
  length before it is solid, so the block compression is s_b = 40 mm;
* *initial rate* k_0 = 80 kN/m = 80 N/mm at the pad. Seen at the wheel centre it is
  k_0 (0.715)^2 = 41 kN/m (0.715 = the pad's vertical speed over the wheel centre's at first
  contact), the order of the 31 kN/m suspension rate (MCU bumpers are sized so that first
  contact is not felt as a knock). The characteristic then gives F(15 mm) = 1.9 kN,
  F(20 mm) = 3.2 kN, F(30 mm) = 9.6 kN, F(34 mm) = 18.1 kN and F(36 mm) = 28.8 kN: a few kN
  at 15-20 mm, above 15 kN near full compression, the shape of the published
  force-deflection curves of MCU jounce bumpers (a long soft start, then a steep wall in the
  last 10-15 % of the stroke);
* *clearance* g = 42 mm at the pad. With the pad 0.215 m from the pivot axis, first contact
  is at an arm rotation asin(0.042 / 0.215) = 11.3 deg, i.e. **58.5 mm of wheel jounce
  relative to the body** from static ride height (front-view four-bar of the corner; the
  PyBullet corner touches within 0.1 mm of it, ``tests/vehicles/test_bump_stop.py``). Why
  that much: Table 4.2 is the *unladen* MPV, and a bumper is placed for the laden car; five
  occupants and luggage put about 100 kg more on a front corner, 100 g / 31 kN/m = 32 mm of
  sag, so 58 mm unladen is about 27 mm laden, the 25-40 mm of free jounce of passenger-car
  fronts. It also reconciles the thesis's two statements on its bump + pothole: the passive
  corner of Ch. 4's validation "did not engage" the bump stop ("low amplitude"), the
  semi-active runs of Ch. 5 hit it on the bump. On our version of that road (1-cos bump
  50 mm x 1.0 m at 34 km/h) the passive corner (3800 N s/m) reaches 53.7 mm of jounce, clear
  of the bumper by 5 mm; with 2000 or 1000 N s/m (a soft semi-active state) it reaches 60
  and 65 mm and touches (0.1 and 0.4 kN). A cobbled durability track with Table 4.5's hub
  levels reaches it on its larger stones;
* at the block (delta = 36 mm, r s_b) the pad has risen 78 mm: 109 mm of wheel jounce
  unladen (about 77 mm laden; total jounce of a small MPV front: 80-110 mm), and the bumper
  carries 28.8 kN, 20.4 kN at the wheel (3.6 times the static corner load of 5.7 kN;
  jounce bumpers are sized for 3-4 g at the wheel).

Not modelled: the bumper's hysteresis (MCU dissipates 10-20 % of the work in a cycle), its
mass, and friction between its tip and the pad. The rebound stop (inside the damper) is not
modelled either.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class BumpStopParams:
    """Jounce-bumper parameters (SI units; see the module docstring for their reasoning)."""

    clearance: float = 0.042
    """g: gap between the bumper tip and the arm's pad at static ride height, along the body's
    vertical [m] (58.5 mm of wheel jounce on the default corner)."""
    initial_rate: float = 80.0e3
    """k_0: rate at first contact [N/m]."""
    stroke: float = 0.040
    """s_b: block compression of the bumper, where the hyperbolic law has its pole [m]."""
    transition: float = 0.9
    """r: fraction of s_b beyond which the law continues along its tangent [-] (0 < r < 1)."""

    def __post_init__(self) -> None:
        if not (self.clearance > 0 and self.initial_rate > 0 and self.stroke > 0):
            raise ValueError("clearance, initial_rate and stroke must be > 0")
        if not 0 < self.transition < 1:
            raise ValueError("transition must be in (0, 1)")


def bump_stop_force(compression: float, params: BumpStopParams | None = None) -> float:
    """Bumper force F [N] (>= 0, compression-positive) at the bumper compression delta [m]
    (delta <= 0: the bumper is free, F = 0). ``compression`` is delta, already net of the
    clearance (see the module docstring)."""
    pr = params or BumpStopParams()
    d = float(compression)
    if d <= 0.0:
        return 0.0
    d_t = pr.transition * pr.stroke
    if d <= d_t:
        return pr.initial_rate * d / (1.0 - d / pr.stroke)
    f_t = pr.initial_rate * d_t / (1.0 - pr.transition)
    return f_t + pr.initial_rate / (1.0 - pr.transition) ** 2 * (d - d_t)


def bump_stop_rate(compression: float, params: BumpStopParams | None = None) -> float:
    """dF/d(delta) [N/m] at the bumper compression delta [m]: 0 while free, k_0 at contact,
    k_0 / (1 - delta/s_b)^2 on the hyperbolic part, k_0 / (1 - r)^2 beyond r s_b."""
    pr = params or BumpStopParams()
    d = float(compression)
    if d <= 0.0:
        return 0.0
    u = min(d / pr.stroke, pr.transition)
    return pr.initial_rate / (1.0 - u) ** 2


def compression(pad_rise: float, body_rise: float, params: BumpStopParams | None = None
                ) -> float:
    """Bumper compression delta [m] from the pad's rise and the bumper mounting's rise (both
    vertical, from static ride height) [m]: delta = pad_rise - body_rise - g (may be < 0)."""
    pr = params or BumpStopParams()
    return float(pad_rise) - float(body_rise) - pr.clearance
