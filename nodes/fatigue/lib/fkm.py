"""The component S-N curve by the FKM guideline (non-welded, local stresses), beside the
Shigley/Marin chain of :mod:`material`.

Source: FKM guideline "Analytical Strength Assessment of Components", 6th ed. (VDMA 2012),
Ch 4 (fatigue assessment with local stresses), for steel (not stainless, not cast). Symbols:

* Tensile strength of the part: Rm = K_d,m · K_A · Rm,N (Rm,N the material's Su). K_d,m the
  technological size factor: 1 for d_eff <= d_eff,N,m, else
  K_d,m = [1 - 0.7686 a_d,m lg(d_eff / 7.5 mm)] / [1 - 0.7686 a_d,m lg(d_eff,N,m / 7.5 mm)]
  (quenched and tempered steel: a_d,m = 0.3, d_eff,N,m = 16 mm); K_A the anisotropy factor
  (1 along the forging's grain flow).
* Material fatigue limit (R = -1, normal stress): σ_W,zd = f_W,σ Rm, f_W,σ = 0.45 for
  "steel other than case-hardening, stainless, forging steels" (817M40 is a quenched and
  tempered steel).
* Roughness factor: K_R,σ = 1 - a_R,σ lg(Rz / µm) lg(2 Rm / Rm,N,min), steel a_R,σ = 0.22,
  Rm,N,min = 400 MPa (Rz 200 µm: rolled or forged skin; 1277 MPa -> 0.592).
* Component fatigue limit with local (notch) stresses from the FE: FKM's design factor
  K_WK = (1/n_σ) [1 + (1/K̃_f)(1/K_R,σ - 1)] / (K_V K_S K_NL,E), taken with K̃_f = n_σ = 1
  (no stress-gradient credit: the FE stress is the notch stress and its gradient is not
  computed) and K_NL,E = 1 (steel), so σ_WK = σ_W,zd · K_R,σ · K_V · K_S (K_V surface
  treatment, K_S coating, both 1: no peening, no coating); ``support_factor`` n_σ > 1
  multiplies σ_WK, for a known gradient.
* S-N line: knee at N_D,σ = 10⁶ cycles, slope k_σ = 5 above it (non-welded steel); below
  the knee the shared endurance rule (:mod:`damage`; FKM's "consistent Miner" variant is
  Haibach's slope 2k - 1 = 9).
* Mean-stress sensitivity: M_σ = a_M · 10⁻³ Rm / MPa + b_M, steel a_M = 0.35, b_M = -0.1
  (1277 MPa -> 0.347), applied by the FKM Haigh diagram (:func:`mean_stress.fkm_amplitude`).
* Temperature factor (FKM 6th ed. Ch 4, K_T,D, for steel other than fine-grained and
  stainless, so for the quenched and tempered 817M40): K_T,D = 1 for -40 °C <= T <= 100 °C,
  K_T,D = 1 - 1.4e-3 (T/°C - 100) above (150 °C: 0.93; 500 °C: 0.44); it multiplies σ_WK.
  FKM covers steel from -40 to 500 °C: a temperature outside is refused
  (:func:`temperature_factor` raises), not extrapolated. M_σ stays the room-temperature one.
* Survival probability: FKM's strengths are for P_ü = 97.5 %. Here the curve is built at any
  probability P with the normal strength scatter of Shigley's Eq 6-29 (8 % coefficient of
  variation: factor 1 - 0.08 z_P), anchored at FKM's 97.5 %: σ_WK(P) = σ_WK(97.5 %)
  (1 - 0.08 z_P) / (1 - 0.08 z_0.975); the median is 1/0.8432 = 1.186 x FKM's value.
  (Haibach's scatter band T_S = 1 : 1.25 for components gives 0.843 at 97.5 % too.)
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from .life_models import SNCurve
from .material import reliability_factor

MPa = 1.0e6
P_FKM = 0.975
"""The survival probability of FKM's strength values."""


T_RANGE_C = (-40.0, 500.0)
"""The temperatures FKM covers for steel (°C)."""


def temperature_factor(T_c: float) -> float:
    """K_T,D at T_c (°C), module docstring; ValueError outside :data:`T_RANGE_C`."""
    lo, hi = T_RANGE_C
    if not lo <= T_c <= hi:
        raise ValueError(f"FKM covers steel from {lo:g} to {hi:g} °C, got {T_c!r} °C")
    return 1.0 if T_c <= 100.0 else 1.0 - 1.4e-3 * (T_c - 100.0)


@dataclass(frozen=True)
class FKMSpec:
    """The FKM factors' inputs (module docstring); SI except Rz (µm, as FKM writes it)."""

    rz_um: float = 200.0
    f_w_sigma: float = 0.45
    a_r_sigma: float = 0.22
    rm_n_min_pa: float = 400e6
    a_m: float = 0.35
    b_m: float = -0.1
    k_slope: float = 5.0
    knee_cycles: float = 1e6
    support_factor: float = 1.0
    k_v: float = 1.0
    k_s: float = 1.0
    k_a: float = 1.0
    d_eff_m: float | None = None
    a_dm: float = 0.3
    d_eff_n_m: float = 0.016

    def __post_init__(self) -> None:
        checks = {"rz_um": (0.0, 1000.0), "f_w_sigma": (0.1, 0.7), "a_r_sigma": (0.0, 0.5),
                  "rm_n_min_pa": (1e6, 2e9), "a_m": (0.0, 1.0), "b_m": (-1.0, 1.0),
                  "k_slope": (2.0, 30.0), "knee_cycles": (1e5, 1e8),
                  "support_factor": (1.0, 3.0), "k_v": (0.5, 3.0), "k_s": (0.1, 1.0),
                  "k_a": (0.5, 1.0), "a_dm": (0.0, 1.0), "d_eff_n_m": (1e-3, 1.0)}
        for k, (lo, hi) in checks.items():
            v = getattr(self, k)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and lo <= v <= hi):
                raise ValueError(f"{k} must be {lo:g}-{hi:g}, got {v!r}")
        if self.d_eff_m is not None and not 1e-3 <= self.d_eff_m <= 1.0:
            raise ValueError(f"d_eff_m must be 0.001-1 m, got {self.d_eff_m!r}")


def size_factor_rm(spec: FKMSpec) -> float:
    """K_d,m (module docstring); 1 when d_eff is not given or <= d_eff,N,m."""
    if spec.d_eff_m is None or spec.d_eff_m <= spec.d_eff_n_m:
        return 1.0
    num = 1.0 - 0.7686 * spec.a_dm * math.log10(spec.d_eff_m / 7.5e-3)
    den = 1.0 - 0.7686 * spec.a_dm * math.log10(spec.d_eff_n_m / 7.5e-3)
    return num / den


def roughness_factor(Rm: float, rz_um: float, a_r: float = 0.22,
                     rm_n_min: float = 400e6) -> float:
    """K_R,σ = 1 - a_R,σ lg(Rz) lg(2 Rm / Rm,N,min) (Rz in µm; 1 for Rz <= 1 µm)."""
    if rz_um <= 1.0:
        return 1.0
    return 1.0 - a_r * math.log10(rz_um) * math.log10(2.0 * Rm / rm_n_min)


def mean_stress_sensitivity(Rm: float, a_m: float = 0.35, b_m: float = -0.1) -> float:
    """M_σ = a_M 10⁻³ Rm/MPa + b_M (at least 0)."""
    return max(0.0, a_m * 1e-3 * Rm / MPa + b_m)


def fkm_factors(Su: float, spec: FKMSpec, P: float = P_FKM,
                temperature_c: float = 20.0) -> dict[str, float]:
    """Every FKM factor and the component fatigue limit σ_WK at survival probability P and
    temperature T (°C) (Pa)."""
    kdm = size_factor_rm(spec)
    Rm = kdm * spec.k_a * Su
    sw = spec.f_w_sigma * Rm
    kr = roughness_factor(Rm, spec.rz_um, spec.a_r_sigma, spec.rm_n_min_pa)
    ktd = temperature_factor(temperature_c)
    swk_975 = sw * kr * spec.k_v * spec.k_s * spec.support_factor * ktd
    p_factor = reliability_factor(P) / reliability_factor(P_FKM)  # 1 - 0.08 z_P
    return {"K_dm": kdm, "K_A": spec.k_a, "Rm_pa": Rm, "f_W_sigma": spec.f_w_sigma,
            "sigma_W_zd_pa": sw, "K_R_sigma": kr, "K_V": spec.k_v, "K_S": spec.k_s,
            "n_sigma": spec.support_factor, "temperature_c": temperature_c, "K_T_D": ktd,
            "sigma_WK_975_pa": swk_975,
            "survival_probability": P, "probability_factor": p_factor,
            "sigma_WK_pa": swk_975 * p_factor,
            "M_sigma": mean_stress_sensitivity(Rm, spec.a_m, spec.b_m)}


def fkm_sn_curve(Su: float, spec: FKMSpec | None = None, endurance: str = "haibach",
                 P: float = 0.5, temperature_c: float = 20.0) -> SNCurve:
    """FKM component S-N curve at survival probability P and temperature T (°C, K_T,D):
    σar = σ_WK (N / N_D)^(-1/k), in
    Basquin form σ'f,c (2N)^b with b = -1/k, σ'f,c = σ_WK (2 N_D)^(1/k); no low-cycle
    segment (FKM's curve is for N >= ~10³; a cycle at σar >= Rm fails at once)."""
    spec = spec or FKMSpec()
    f = fkm_factors(Su, spec, P, temperature_c)
    b = -1.0 / spec.k_slope
    knee_rev = 2.0 * spec.knee_cycles
    swk = f["sigma_WK_pa"]
    return SNCurve(sf=swk * knee_rev ** (-b), b=b, Se=swk, knee_reversals=knee_rev,
                   endurance=endurance, name="component (FKM guideline, non-welded)",
                   meta={"method": "FKM guideline Analytical Strength Assessment, 6th ed. "
                                   "(2012), Ch 4, non-welded steel, local stresses",
                         "sn_method": "fkm", "factors": f, "spec": asdict(spec),
                         "mean_stress_sensitivity": f["M_sigma"],
                         "knee_cycles": spec.knee_cycles, "k": spec.k_slope})
