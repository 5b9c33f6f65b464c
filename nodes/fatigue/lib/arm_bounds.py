"""How stiff an arm of a given mass must be to carry a bending moment at a given stress: the
closed form that ties the first bending mode to the nominal bending stress.

A beam of mass m [kg] and length L [m] (section area A = m / (ρ L), second moment I, radius of
gyration r = sqrt(I / A), extreme fibre c) has its first free-free bending mode at

    ω = (βL)² sqrt(E I / (m L³))          (βL = 4.730 for a uniform beam)

and carries a moment M [N m] at the nominal stress σ = M c / I. Write κ = r / c (the section's
efficiency: 1/sqrt(3) for a solid rectangle, → 1 for an I-section whose flanges hold all the
material; κ ≤ 1 for every section, since no material lies farther than c from the neutral
axis). Eliminating I and A:

    σ = M (βL)² sqrt(ρ E) / (κ ω m L)

so for a given mass, length and moment, **the softer the arm (lower ω), the higher its stress**,
and with κ ≤ 1 no section shape beats σ_floor = M (βL)² sqrt(ρ E) / (ω m L). For the uniform
beam this is exact (Euler-Bernoulli); a tapered arm or one with heavy joint bosses has another
βL (of the same order), so for the arm it is an estimate, checked against the FE design family in
``python -m bench arm-design-space``. Issue #12 asks for a 5 kg arm whose first mode is
within 15 % of Table 6.1's 362 Hz and whose static hot spot is below 250 MPa, with the torsion
spring's 1.58 kN m at the pivot (Table 4.2's K_θ): this floor says why both cannot hold at once
(docs/fatigue.md).
"""

from __future__ import annotations

import math

BETA_L_FREE_FREE = 4.730041
"""First root of cos(βL) cosh(βL) = 1: the uniform free-free beam's first bending mode [-]."""


def nominal_bending_stress(moment: float, mass: float, length: float, frequency_hz: float,
                           E: float, rho: float, kappa: float = 1.0,
                           beta_l: float = BETA_L_FREE_FREE) -> float:
    """Nominal bending stress σ [Pa] of a uniform beam of mass [kg] and length [m] whose first
    free-free bending mode is ``frequency_hz``, carrying ``moment`` [N m]; κ = r / c the section
    efficiency (1 gives the floor over all section shapes). E [Pa], ρ [kg/m³]."""
    if min(mass, length, frequency_hz, E, rho, kappa) <= 0.0 or kappa > 1.0:
        raise ValueError("mass, length, frequency, E, rho must be > 0 and 0 < kappa <= 1")
    omega = 2.0 * math.pi * frequency_hz
    return abs(moment) * beta_l ** 2 * math.sqrt(rho * E) / (kappa * omega * mass * length)
