"""Material and component fatigue properties: 817M40 (thesis Table 6.2), the Uniform Material
Law, and the Marin factors that turn the material into the forged lower arm.

Symbols (SI, stresses in Pa):
    E: Young's modulus; nu: Poisson's ratio; rho: density (kg/m^3);
    Su (σu, Sut): ultimate tensile strength; Sy (σy): yield strength;
    sf (σ'f): fatigue strength coefficient; b: fatigue strength exponent;
    ef (ε'f): fatigue ductility coefficient; c: fatigue ductility exponent;
    K (K'): cyclic strength coefficient; n (n'): cyclic strain-hardening exponent;
    Se (Se'): endurance limit of the polished rotating-beam specimen (stress amplitude).

Strain-life (Coffin-Manson-Basquin): εa = σ'f/E (2Nf)^b + ε'f (2Nf)^c.
Cyclic stress-strain curve (Ramberg-Osgood): εa = σa/E + (σa/K')^(1/n').

**Material.** Table 6.2 of the thesis gives ρ, σy, σu, E, ν, K' and n' for 817M40 (from Haiba).
It gives no σ'f, b, ε'f, c and no endurance limit. All six strain-life constants are taken from
one source, the **Uniform Material Law** of Bäumel & Seeger (1990) for unalloyed and low-alloy
steels:
    σ'f = 1.5 σu, b = -0.087, ε'f = 0.59 ψ, c = -0.58, K' = 1.65 σu, n' = 0.15,
    ψ = 1 if σu/E <= 0.003 else 1.375 - 125 σu/E.
Its K', n' are nearly compatible with its σ'f, ε'f, b, c (`compatibility`: n' = b/c = 0.15
exactly; σ'f/ε'f^(b/c) = 2252 MPa against 1.65 σu = 2107 MPa, 6.4 % below). Table 6.2's
K' = 1166 MPa, n' = 0.0246 are **not** used by default: n' = 0.0246 means practically no cyclic
hardening (a flat cyclic curve at ≈ 1000 MPa from 0.2 % strain on) and is incompatible with any
b, c of a steel (b/c = 0.0246 would need c ≈ -3.5), and K' equal to σy to the MPa suggests a
column slip in the table. They stay available (``cyclic="table_6_2"``), as does the exactly
compatible pair (``cyclic="compatible"``: K' = σ'f/ε'f^(b/c), n' = b/c).

Se' = 0.5 σu for σu <= 1400 MPa, 700 MPa above (Shigley's Mechanical Engineering Design, 9th
ed., Budynas & Nisbett 2011, Eq 6-8): the polished specimen's endurance limit, the start of the
Marin chain.

**Component (Marin, Shigley 9th ed. Sec 6-9):** Se = ka kb kc kd ke kf Se', with
    ka = a Sut^b (Table 6-2, Sut in MPa, Noll & Lipson 1946), surface;
    kb = (d/7.62)^-0.107 ≈ 1.24 d^-0.107 (2.79 <= d <= 51 mm; 1 for the 7.62 mm specimen),
         1.51 d^-0.157 (51 < d <= 254 mm) for bending
         (Eq 6-20), 1 for axial loading (Eq 6-21); d the equivalent diameter, for a
         non-rotating rectangular section h x b: d_e = 0.808 sqrt(h b) (Eq 6-25);
    kc = 1 bending, 0.85 axial (Table 6-11 average);
    kd = 1 at room temperature, Eq 6-27 above 70 °F (21 °C) up to 1000 °F (538 °C);
    ke = 1 - 0.08 z_a (Eq 6-29), z_a the standard normal variate of the reliability R
         (0.868 at 95 %, 0.814 at 99 %, 0.753 at 99.9 %; Table 6-5);
    kf = miscellaneous effects (residual stress from peening, corrosion, ...): 1 unless known.
The notch factor Kf is *not* applied: the FE gives the local (notch) stress.

Finite life (Shigley Eq 6-10 to 6-16): the line S = a N^B through (10³, f Sut) and (Ne, Se),
Ne = 10⁶ cycles, f = σ'F/Sut (2·10³)^b' with σ'F = Sut + 345 MPa and b' = -log(σ'F/Se')/
log(2 Ne) (Fig 6-18; f = 0.9 for Sut < 490 MPa); below 10³ cycles the conservative line from
(1, Sut) to (10³, f Sut). In Basquin form σar = σ'f,c (2N)^b_c with b_c = B, σ'f,c = a 2^-B.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace
from statistics import NormalDist
from typing import TYPE_CHECKING, Any

from .life_models import SNCurve

if TYPE_CHECKING:
    from .sn_data import TabulatedSN

MPa = 1.0e6

# Accepted override names -> field name (primes allowed, as durability engineers write them).
ALIASES = {
    "E": "E", "nu": "nu", "rho": "rho", "Su": "Su", "Sy": "Sy",
    "sf": "sf", "sf'": "sf", "b": "b", "ef": "ef", "ef'": "ef", "c": "c",
    "K": "K", "K'": "K", "n": "n", "n'": "n", "Se": "Se",
}

CYCLIC_CURVES = ("uml", "table_6_2", "compatible")
"""Sources of K', n': Bäumel-Seeger UML (default), thesis Table 6.2, or K' = σ'f/ε'f^(b/c)."""


@dataclass(frozen=True)
class Material:
    """Elastic and fatigue properties, SI units (Pa, kg/m^3); see module docstring.

    ``sn`` is the stress-life curve used for damage (a component curve from
    `component_sn_curve`); ``None`` means the material's own Basquin line σ'f (2Nf)^b with the
    endurance limit Se and no endurance treatment (`material_sn_curve` with ``"none"``).
    """

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
    sn: SNCurve | TabulatedSN | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        for k in ("E", "rho", "Su", "Sy", "sf", "ef", "K", "n", "Se"):
            v = getattr(self, k)
            if not (math.isfinite(v) and v > 0.0):
                raise ValueError(f"{k} must be a finite number > 0, got {v!r}")
        for k in ("b", "c"):
            v = getattr(self, k)
            if not (math.isfinite(v) and v < 0.0):
                raise ValueError(f"{k} must be a finite negative exponent, got {v!r}")
        if not 0.0 <= self.nu < 0.5:
            raise ValueError(f"nu must be in [0, 0.5), got {self.nu!r}")

    def as_dict(self) -> dict[str, float | str]:
        out: dict[str, float | str] = {"name": self.name}
        for f in fields(self):
            if f.name not in ("name", "source", "sn"):
                out[f.name] = getattr(self, f.name)
        return out


def uniform_material_law(Su: float, E: float) -> dict[str, float]:
    """Bäumel-Seeger Uniform Material Law for steels: σ'f, b, ε'f, c, K', n' (Pa)."""
    psi = 1.0 if Su / E <= 0.003 else 1.375 - 125.0 * Su / E
    return {
        "sf": 1.5 * Su, "b": -0.087, "ef": 0.59 * psi, "c": -0.58,
        "K": 1.65 * Su, "n": 0.15,
    }


def specimen_endurance_limit(Su: float) -> float:
    """Se' (Pa) of the polished rotating-beam specimen: 0.5 Su up to 1400 MPa, else 700 MPa."""
    return 0.5 * Su if Su <= 1400 * MPa else 700 * MPa


_REQUIRED = ("E", "nu", "rho", "Su", "Sy")
_OPTIONAL = ("sf", "b", "ef", "c", "K", "n", "Se", "K_table", "n_table")
"""A database entry's required and optional numbers (SI units, as `Material`)."""


def material_from_entry(name: str, entry: Mapping[str, Any], cyclic: str = "uml",
                        base: Mapping[str, float] | None = None) -> Material:
    """Material ``name`` from its database ``entry`` (a table of the database file, read by
    :mod:`nodes.fatigue.materials`): its values with their sources; each strain-life
    constant it lacks from the UML, Se' from Shigley Eq 6-8 if absent.

    ``base`` replaces the entry's E, nu, rho, Su, Sy *before* those estimates, so that the
    estimated values follow an overridden strength (σ'f = 1.5 Su, Se' = 0.5 Su, ...; a
    value the entry gives itself stays).

    ``cyclic`` chooses K', n': "uml" (the entry's K, n, else 1.65 σu, 0.15), "table_6_2"
    (the entry's K_table, n_table) or "compatible" (σ'f/ε'f^(b/c), b/c).
    """
    if cyclic not in CYCLIC_CURVES:
        raise ValueError(f"cyclic must be one of {CYCLIC_CURVES}, got {cyclic!r}")
    e = dict(entry)
    src_file = dict(e.get("source") or {})
    for k, v in (base or {}).items():
        if k not in _REQUIRED:
            raise ValueError(f"base may replace {_REQUIRED} only, got {k!r}")
        e[k] = float(v)
        src_file[k] = "scenario override"
    Su, E = float(e["Su"]), float(e["E"])
    uml = uniform_material_law(Su, E)
    est = "Uniform Material Law (Bäumel & Seeger 1990)"

    def given(k: str) -> str:  # the source of a value the entry gives
        return str(src_file.get(k, f"material database [{name}]"))

    vals: dict[str, float] = {}
    source: dict[str, str] = {}
    for k in ("E", "nu", "rho", "Su", "Sy"):
        vals[k], source[k] = float(e[k]), given(k)
    for k in ("sf", "b", "ef", "c", *(("K", "n") if cyclic == "uml" else ())):
        vals[k], source[k] = (float(e[k]), given(k)) if k in e else (uml[k], est)
    if cyclic == "table_6_2":
        if "K_table" not in e or "n_table" not in e:
            raise ValueError(f"material {name!r} has no K_table, n_table for "
                             'cyclic = "table_6_2"')
        vals["K"], vals["n"] = float(e["K_table"]), float(e["n_table"])
        source["K"] = str(src_file.get("K_table", "material database"))
        source["n"] = str(src_file.get("n_table", "material database"))
    elif cyclic == "compatible":
        vals["n"] = vals["b"] / vals["c"]
        vals["K"] = vals["sf"] / vals["ef"] ** vals["n"]
        source["K"] = source["n"] = "compatible with σ'f, ε'f, b, c (Eq 6.7, 6.8)"
    if "Se" in e:
        vals["Se"], source["Se"] = float(e["Se"]), given("Se")
    else:
        vals["Se"] = specimen_endurance_limit(Su)
        source["Se"] = ("Se' = 0.5 Su (Shigley 9th ed. Eq 6-8, Su <= 1400 MPa)"
                        if Su <= 1400 * MPa else "Se' = 700 MPa (Shigley 9th ed. Eq 6-8)")
    return Material(name=name, E=vals["E"], nu=vals["nu"], rho=vals["rho"], Su=vals["Su"],
                    Sy=vals["Sy"], sf=vals["sf"], b=vals["b"], ef=vals["ef"], c=vals["c"],
                    K=vals["K"], n=vals["n"], Se=vals["Se"], source=source)


def with_overrides(mat: Material, overrides: Mapping[str, float]) -> Material:
    """Return ``mat`` with some properties replaced (keys as in `ALIASES`, SI units); its
    name then says so ("817M40 with Su, Sy overridden"): it is no longer the database's.

    Raises KeyError for an unknown name and ValueError for a non-finite value; the config
    layer turns both into a ScenarioError naming the key.
    """
    changes: dict[str, Any] = {}  # field name -> new value (each a float field)
    src = dict(mat.source)
    for key, value in overrides.items():
        if key not in ALIASES:
            raise KeyError(key)
        v = float(value)
        if not math.isfinite(v):
            raise ValueError(key)
        changes[ALIASES[key]] = v
        src[ALIASES[key]] = "scenario override"
    name = mat.name
    if changes:
        name = f"{mat.name} with {', '.join(changes)} overridden"
    return replace(mat, name=name, source=src, **changes)


def compatibility(mat: Material) -> dict[str, float]:
    """K' and n' implied by the strain-life constants (thesis Eq 6.7, 6.8).

    K' = σ'f / ε'f^(n'), n' = b / c; compare with the cyclic-curve values used
    (``K_ratio`` = K_used / K_implied).
    """
    n_implied = mat.b / mat.c
    K_implied = mat.sf / mat.ef**n_implied
    return {"K_implied": K_implied, "n_implied": n_implied,
            "K_used": mat.K, "n_used": mat.n, "K_ratio": mat.K / K_implied}


# ----------------------------------------------------------------------------- Marin factors
SURFACE_FACTORS: dict[str, tuple[float, float]] = {
    "polished": (1.0, 0.0),
    "ground": (1.58, -0.085),
    "machined": (4.51, -0.265),
    "cold_drawn": (4.51, -0.265),
    "hot_rolled": (57.7, -0.718),
    "forged": (272.0, -0.995),
}
"""Surface -> (a [MPa^-b], b) of ka = a Sut^b, Sut in MPa (Shigley 9th ed. Table 6-2, from Noll
& Lipson 1946); "polished" is the specimen itself (ka = 1). ka is capped at 1."""

LOADINGS = {"bending": 1.0, "axial": 0.85}
"""Loading -> kc (Shigley 9th ed. Table 6-11, average for axial)."""


def surface_factor(Su: float, surface: str) -> float:
    """ka = a Sut^b (Sut in MPa), at most 1 (Shigley Eq 6-19, Table 6-2)."""
    if surface not in SURFACE_FACTORS:
        raise ValueError(f"surface must be one of {tuple(SURFACE_FACTORS)}, got {surface!r}")
    a, b = SURFACE_FACTORS[surface]
    return min(1.0, a * (Su / MPa) ** b)


def rectangle_equivalent_diameter(h: float, b: float) -> float:
    """d_e (m) of a non-rotating rectangular section h x b (m) in bending: 0.808 sqrt(h b).

    Shigley Eq 6-25: the area stressed above 95 % of the maximum, 0.05 h b, equated to that of
    a rotating round bar, 0.0766 d_e².
    """
    if not (h > 0.0 and b > 0.0 and math.isfinite(h * b)):
        raise ValueError(f"section h, b must be > 0, got {h!r}, {b!r}")
    return 0.808 * math.sqrt(h * b)


def size_factor(d_e: float, loading: str = "bending") -> float:
    """kb from the equivalent diameter d_e (m); 1 for axial loading (Shigley Eq 6-20, 6-21).

    (d/7.62 mm)^-0.107 up to 51 mm (Shigley's "= 1.24 d^-0.107" is its rounding), then
    1.51 d^-0.157 (d in mm) up to 254 mm.
    """
    if loading not in LOADINGS:
        raise ValueError(f"loading must be one of {tuple(LOADINGS)}, got {loading!r}")
    if loading == "axial":
        return 1.0
    d = d_e * 1e3
    if not 2.79 <= d <= 254.0:
        raise ValueError(f"equivalent diameter must be 2.79-254 mm, got {d:.4g} mm")
    return (d / 7.62) ** -0.107 if d <= 51.0 else 1.51 * d**-0.157


def temperature_factor(T_c: float) -> float:
    """kd at T_c (°C): 1 up to 21.1 °C (70 °F), Shigley Eq 6-27 (T in °F) up to 537.8 °C."""
    if not -60.0 <= T_c <= 537.8:
        raise ValueError(f"temperature must be -60 to 537.8 °C, got {T_c!r}")
    if T_c <= (70.0 - 32.0) / 1.8:
        return 1.0
    T = 1.8 * T_c + 32.0
    return (0.975 + 0.432e-3 * T - 0.115e-5 * T**2 + 0.104e-8 * T**3 - 0.595e-12 * T**4)


def reliability_factor(R: float) -> float:
    """ke = 1 - 0.08 z_a, z_a the standard normal variate of reliability R (Shigley Eq 6-29)."""
    if not 0.5 <= R <= 0.999999:
        raise ValueError(f"reliability must be 0.5-0.999999, got {R!r}")
    return 1.0 - 0.08 * NormalDist().inv_cdf(R)


def fatigue_strength_fraction(Su: float, Se_prime: float, Ne: float = 1e6) -> float:
    """f of Shigley Eq 6-10 (Fig 6-18): (S'f at 10³ cycles) / Sut, for Se' at Ne cycles.

    f = σ'F/Sut (2·10³)^b', σ'F = Sut + 345 MPa (Eq 6-11), b' = -log10(σ'F/Se')/log10(2 Ne)
    (Eq 6-12); f = 0.9 for Sut < 490 MPa (70 kpsi) as Shigley recommends.
    """
    if Su < 490 * MPa:
        return 0.9
    sF = Su + 345 * MPa
    bp = -math.log10(sF / Se_prime) / math.log10(2.0 * Ne)
    return sF / Su * (2.0e3) ** bp


@dataclass(frozen=True)
class ComponentSpec:
    """What the Marin factors of a component depend on (validated when built).

    surface: a key of `SURFACE_FACTORS`; section_h_m, section_b_m: depth and width (m) of the
    rectangle whose equivalent diameter gives kb, or ``d_e_m`` (m) given directly (it wins);
    loading: "bending" or "axial"; reliability: R (0.5 = median curve); temperature_c: °C;
    kf: miscellaneous-effects factor (0 < kf <= 2); knee_cycles: Ne, cycles at Se.
    """

    surface: str = "forged"
    section_h_m: float = 0.042
    section_b_m: float = 0.022
    d_e_m: float | None = None
    loading: str = "bending"
    reliability: float = 0.5
    temperature_c: float = 20.0
    kf: float = 1.0
    knee_cycles: float = 1e6

    def __post_init__(self) -> None:
        if self.surface not in SURFACE_FACTORS:
            raise ValueError(f"surface must be one of {tuple(SURFACE_FACTORS)}, "
                             f"got {self.surface!r}")
        if self.loading not in LOADINGS:
            raise ValueError(f"loading must be one of {tuple(LOADINGS)}, got {self.loading!r}")
        if self.d_e_m is None:
            rectangle_equivalent_diameter(self.section_h_m, self.section_b_m)
        size_factor(self.equivalent_diameter_m, self.loading)
        reliability_factor(self.reliability)
        temperature_factor(self.temperature_c)
        if not (math.isfinite(self.kf) and 0.0 < self.kf <= 2.0):
            raise ValueError(f"kf must be in (0, 2], got {self.kf!r}")
        if not 1e5 <= self.knee_cycles <= 1e8:
            raise ValueError(f"knee_cycles must be 1e5-1e8, got {self.knee_cycles!r}")

    @property
    def equivalent_diameter_m(self) -> float:
        if self.d_e_m is not None:
            return self.d_e_m
        return rectangle_equivalent_diameter(self.section_h_m, self.section_b_m)


@dataclass(frozen=True)
class MarinFactors:
    """Marin factors and the component endurance limit Se = ka kb kc kd ke kf Se' (Pa)."""

    ka: float
    kb: float
    kc: float
    kd: float
    ke: float
    kf: float
    Se_prime: float
    d_e_m: float

    @property
    def product(self) -> float:
        return self.ka * self.kb * self.kc * self.kd * self.ke * self.kf

    @property
    def Se(self) -> float:
        return self.product * self.Se_prime

    def as_dict(self) -> dict[str, float]:
        return {"ka": self.ka, "kb": self.kb, "kc": self.kc, "kd": self.kd, "ke": self.ke,
                "kf": self.kf, "product": self.product, "equivalent_diameter_m": self.d_e_m,
                "Se_prime_pa": self.Se_prime, "Se_pa": self.Se}


def marin_factors(mat: Material, spec: ComponentSpec) -> MarinFactors:
    """Marin factors of ``spec`` for material ``mat`` (Se' = mat.Se)."""
    d_e = spec.equivalent_diameter_m
    return MarinFactors(
        ka=surface_factor(mat.Su, spec.surface),
        kb=size_factor(d_e, spec.loading),
        kc=LOADINGS[spec.loading],
        kd=temperature_factor(spec.temperature_c),
        ke=reliability_factor(spec.reliability),
        kf=spec.kf,
        Se_prime=mat.Se,
        d_e_m=d_e,
    )


def component_sn_curve(mat: Material, spec: ComponentSpec | None = None,
                       endurance: str = "haibach") -> SNCurve:
    """The component's S-N curve (Shigley Eq 6-13 to 6-16) in Basquin form.

    S = a N^B through (10³, f Sut) and (Ne, Se): B = log10(f Sut/Se)/log10(10³/Ne),
    a = f Sut / 10^(3B); σar = σ'f,c (2N)^b_c with b_c = B and σ'f,c = a 2^-B; the knee at
    (2 Ne, Se); below 10³ cycles the line (1, Sut)-(10³, f Sut). ``endurance`` is the
    treatment below the knee (see `SNCurve`).
    """
    spec = spec or ComponentSpec()
    m = marin_factors(mat, spec)
    f = fatigue_strength_fraction(mat.Su, mat.Se, spec.knee_cycles)
    S3 = f * mat.Su
    Se = m.Se
    if not Se < S3:
        raise ValueError(f"component Se {Se / MPa:.4g} MPa must be below f Sut "
                         f"{S3 / MPa:.4g} MPa")
    B = math.log10(S3 / Se) / math.log10(1e3 / spec.knee_cycles)
    a = S3 / 10.0 ** (3.0 * B)
    return SNCurve(
        sf=a * 2.0 ** (-B), b=B, Se=Se, knee_reversals=2.0 * spec.knee_cycles,
        endurance=endurance, lcf_Su=mat.Su, lcf_reversals=2.0e3,
        name="component (Marin, Shigley 9th ed.)",
        meta={"method": "Marin factors, Shigley's Mechanical Engineering Design 9th ed. "
                        "(Budynas & Nisbett 2011) Sec 6-9, Eq 6-8 to 6-29",
              "surface": spec.surface, "loading": spec.loading,
              "reliability": spec.reliability, "temperature_c": spec.temperature_c,
              "section_h_m": None if spec.d_e_m is not None else spec.section_h_m,
              "section_b_m": None if spec.d_e_m is not None else spec.section_b_m,
              "knee_cycles": spec.knee_cycles,
              "factors": m.as_dict(), "f": f, "f_Sut_pa": S3,
              "shigley_a_pa": a, "shigley_b": B},
    )


def material_sn_curve(mat: Material, endurance: str = "none") -> SNCurve:
    """The material's own (polished specimen) Basquin line σ'f (2Nf)^b, knee where it meets
    Se (mat.Se), no low-cycle segment."""
    return SNCurve(sf=mat.sf, b=mat.b, Se=mat.Se, knee_reversals=(mat.Se / mat.sf) ** (1 / mat.b),
                   endurance=endurance, name="material (UML Basquin, polished specimen)",
                   meta={"method": "material Basquin line σ'f (2N)^b, knee at Se"})
