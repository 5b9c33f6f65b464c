"""Jounce bumper (bump stop) of the realistic front corner: a pure force law, no I/O.

The thesis's realistic corner had a bump stop (Table 4.1's translational "bump stop" joint;
Ch. 5 sees it hit on the bump, Table 4.5 explains the pavé's lateral levels by it) but gives
none of its numbers; these are ours.

**Where it acts.** A microcellular polyurethane (MCU) jounce bumper hangs from the body above
the lower arm's pad (:data:`cosim.lower_arm.BUMP_STOP_PAD`, 0.215 m outboard of the pivot
axis, 0.73 of the ball-joint lever). Its compression along the body's vertical is

    delta = (z_pad - z_pad,0) - (z_bumper - z_bumper,0) - g            [m]

(heights from static ride height, g the tip-to-pad clearance there). For delta <= 0 it is
free; F_bs = F(delta) >= 0 pushes the body up and the pad down, along the body's vertical
(applied by :mod:`nodes.plant.double_wishbone`).

**Characteristic** (compression-positive force F [N] of delta [m]):

    F(delta) = k_0 delta / (1 - delta / s_b)                 for 0 < delta <= r s_b
    F(delta) = F(r s_b) + k_1 (delta - r s_b),  k_1 = k_0 / (1 - r)^2   beyond,

a hyperbolic progression: rate k_0 at first contact (the soft tip buckling), doubled by
delta = 0.29 s_b, unbounded as the cells close towards the block compression s_b. Past
r s_b (r = 0.9, rate 100 k_0) it continues along its tangent: finite, monotonic and C1 if
an impact drives delta past the block (a pole at s_b would change sign under a fixed step).

**Numbers** (:class:`BumpStopParams` defaults) and why:

* *bumper*: MCU, ~60 mm free length (C-segment cars, small MPVs), solid at about a third of
  it: block compression s_b = 40 mm;
* *initial rate* k_0 = 80 kN/m at the pad, k_0 (0.715)^2 = 41 kN/m at the wheel centre
  (0.715: pad over wheel-centre speed at contact), the order of the 31 kN/m suspension rate
  (first contact not felt as a knock). Then F(15, 20, 30, 34, 36 mm) = 1.9, 3.2, 9.6, 18.1,
  28.8 kN: a long soft start, then a steep wall in the last 10-15 % of the stroke, the shape
  of published MCU force-deflection curves;
* *clearance* g = 42 mm at the pad: first contact at an arm rotation asin(0.042 / 0.215) =
  11.3 deg, **58.5 mm of wheel jounce relative to the body** (the PyBullet corner touches
  within 0.1 mm of it, ``tests/vehicles/test_bump_stop.py``). Table 4.2 is the *unladen*
  MPV; a laden front corner (+100 kg: 100 g / 31 kN/m = 32 mm of sag) keeps ~27 mm, the
  25-40 mm of passenger-car fronts. It also fits the thesis's bump + pothole: the passive
  corner of Ch. 4 "did not engage" the bump stop, the semi-active runs of Ch. 5 hit it. On
  our version of that road (1-cos bump 50 mm x 1.0 m at 34 km/h) the passive corner
  (3800 N s/m) reaches 53.7 mm, 5 mm clear; with 2000 or 1000 N s/m it reaches 60 and
  65 mm and touches (0.1 and 0.4 kN). A pavé with Table 4.5's hub levels reaches it on its
  larger stones;
* at the block (delta = 36 mm, r s_b) the pad has risen 78 mm: 109 mm of wheel jounce
  unladen (~77 mm laden; small MPV fronts: 80-110 mm), 28.8 kN on the bumper, 20.4 kN at
  the wheel (3.6 times the 5.7 kN static corner load; bumpers are sized for 3-4 g).

Not modelled: the bumper's hysteresis (MCU dissipates 10-20 % a cycle), its mass, tip
friction, and the rebound stop (inside the damper).
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


def compression(pad_rise: float, body_rise: float, params: BumpStopParams | None = None
                ) -> float:
    """Bumper compression delta [m] from the pad's rise and the bumper mounting's rise (both
    vertical, from static ride height) [m]: delta = pad_rise - body_rise - g (may be < 0)."""
    pr = params or BumpStopParams()
    return float(pad_rise) - float(body_rise) - pr.clearance
