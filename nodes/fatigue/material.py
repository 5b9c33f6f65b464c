"""Material data for fatigue: 817M40 (thesis Table 6.2) and the Uniform Material Law.

Symbols (SI, stresses in Pa):
    E: Young's modulus; nu: Poisson's ratio; rho: density (kg/m^3);
    Su (σu): ultimate tensile strength; Sy (σy): yield strength;
    sf (σ'f): fatigue strength coefficient; b: fatigue strength exponent;
    ef (ε'f): fatigue ductility coefficient; c: fatigue ductility exponent;
    K (K'): cyclic strength coefficient; n (n'): cyclic strain-hardening exponent;
    Se: fully reversed endurance limit (stress amplitude), used only if asked for.

Strain-life (Coffin-Manson-Basquin): εa = σ'f/E (2Nf)^b + ε'f (2Nf)^c.
Cyclic stress-strain curve (Ramberg-Osgood): εa = σa/E + (σa/K')^(1/n').

Table 6.2 of the thesis gives ρ, σy, σu, E, ν, K' and n' for 817M40 (from Haiba). It gives no
σ'f, b, ε'f, c and no endurance limit; they are estimated here by the **Uniform Material Law**
of Bäumel & Seeger (1990) for unalloyed and low-alloy steels:
    σ'f = 1.5 σu, b = -0.087, ε'f = 0.59 ψ, c = -0.58,
    ψ = 1 if σu/E <= 0.003 else 1.375 - 125 σu/E,
and Se = 0.5 σu (Shigley/Juvinall estimate of the polished rotating-beam endurance limit of
steels with σu <= 1400 MPa). UML would also give K' = 1.65 σu, n' = 0.15; the thesis's own K'
and n' (1166 MPa, 0.0246) are kept for the cyclic curve (Neuber), as Table 6.2 prints them, even
though they are not compatible with σ'f/ε'f^(n') and b/c (see `compatibility`). Every value can
be overridden in the scenario (``fatigue.material.<name>``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace

MPa = 1.0e6

# Accepted override names -> field name (primes allowed, as durability engineers write them).
ALIASES = {
    "E": "E", "nu": "nu", "rho": "rho", "Su": "Su", "Sy": "Sy",
    "sf": "sf", "sf'": "sf", "b": "b", "ef": "ef", "ef'": "ef", "c": "c",
    "K": "K", "K'": "K", "n": "n", "n'": "n", "Se": "Se",
}


@dataclass(frozen=True)
class Material:
    """Elastic and fatigue properties, SI units (Pa, kg/m^3); see module docstring."""

    name: str
    E: float
    nu: float
    rho: float
    Su: float
    Sy: float
    sf: float
    b: float
    ef: float
    c: float
    K: float
    n: float
    Se: float
    source: Mapping[str, str] = field(default_factory=dict, compare=False)

    def as_dict(self) -> dict[str, float | str]:
        out: dict[str, float | str] = {"name": self.name}
        for f in fields(self):
            if f.name not in ("name", "source"):
                out[f.name] = getattr(self, f.name)
        return out


def uniform_material_law(Su: float, E: float) -> dict[str, float]:
    """Bäumel-Seeger Uniform Material Law for steels: σ'f, b, ε'f, c, K', n' (Pa)."""
    psi = 1.0 if Su / E <= 0.003 else 1.375 - 125.0 * Su / E
    return {
        "sf": 1.5 * Su, "b": -0.087, "ef": 0.59 * psi, "c": -0.58,
        "K": 1.65 * Su, "n": 0.15,
    }


def steel_817M40() -> Material:
    """817M40 hardened and tempered (≈ EN24T / AISI 4340): Table 6.2 + UML estimates."""
    Su, E = 1277 * MPa, 200e9
    uml = uniform_material_law(Su, E)
    t62 = "thesis Table 6.2"
    est = "estimated: Uniform Material Law (Bäumel & Seeger 1990)"
    return Material(
        name="817M40",
        E=E, nu=0.3, rho=7800.0, Su=Su, Sy=1166 * MPa,
        sf=uml["sf"], b=uml["b"], ef=uml["ef"], c=uml["c"],
        K=1166 * MPa, n=0.0246,
        Se=0.5 * Su,
        source={
            "E": t62, "nu": t62, "rho": t62, "Su": t62, "Sy": t62, "K": t62, "n": t62,
            "sf": est, "b": est, "ef": est, "c": est,
            "Se": "estimated: Se = 0.5 Su (Shigley/Juvinall, Su <= 1400 MPa)",
        },
    )


def with_overrides(mat: Material, overrides: Mapping[str, float]) -> Material:
    """Return ``mat`` with some properties replaced (keys as in `ALIASES`, SI units).

    Raises KeyError for an unknown name and ValueError for a non-finite value; the config
    layer turns both into a ScenarioError naming the key.
    """
    changes: dict[str, float] = {}
    src = dict(mat.source)
    for key, value in overrides.items():
        if key not in ALIASES:
            raise KeyError(key)
        v = float(value)
        if not math.isfinite(v):
            raise ValueError(key)
        changes[ALIASES[key]] = v
        src[ALIASES[key]] = "scenario override"
    return replace(mat, source=src, **changes)


def compatibility(mat: Material) -> dict[str, float]:
    """K' and n' implied by the strain-life constants (thesis Eq 6.7, 6.8).

    K' = σ'f / ε'f^(n'), n' = b / c; compare with the cyclic-curve values used.
    """
    n_implied = mat.b / mat.c
    return {"K_implied": mat.sf / mat.ef**n_implied, "n_implied": n_implied,
            "K_used": mat.K, "n_used": mat.n}
