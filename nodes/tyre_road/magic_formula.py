"""Magic Formula 6.1 tyre (Pacejka, *Tire and Vehicle Dynamics*, 3rd ed., 2012, Sec. 4.3.2,
Eqs. 4.E1-4.E78; the same as the MF-Tyre/MF-Swift 6.1.2 equation manual), steady state, as a
pure model: no I/O, numpy in, numpy out.

Inputs (ISO-W axes, the .tir file's convention; SI): ``Fz`` vertical load [N] (> 0 in
compression), ``kappa`` longitudinal slip [-] (-1: locked wheel), ``alpha`` slip angle
[rad], ``gamma`` inclination angle [rad], ``Vx`` forward speed of the wheel centre [m/s],
``p`` inflation pressure [Pa] (default the file's INFLPRES). Outputs: ``Fx``, ``Fy`` [N],
``Mz`` aligning moment [N m], the pure-slip ``Fx0``, ``Fy0``, ``Mz0``, the slip stiffnesses
``Kxk`` = dFx0/dkappa [N], ``Kya`` = dFy0/dalpha [N/rad], the friction coefficients ``mux``,
``muy``, the pneumatic trail ``t`` [m], the residual moment ``Mzr`` [N m], and the
relaxation lengths ``sigma_x``, ``sigma_y`` [m] of MF 6.1 (Kxk / Cx, |Kya| / Cy with the
tyre's overall stiffnesses Cx, Cy of [STRUCTURAL]).

What is and is not in (a choice of this port, written where it matters below):

* turn slip is off (every zeta = 1: Pacejka's "phi = 0"), as MFeval's use mode x11;
* the input limits of the .tir ([VERTICAL_FORCE_RANGE], [LONG_SLIP_RANGE], [SLIP_ANGLE_RANGE],
  [INCLINATION_ANGLE_RANGE], [INFLATION_PRESSURE_RANGE]) are applied by clipping, as MF-Tyre
  does with its limits check on;
* no low-speed reduction below VXLOW (the slip then comes from the caller, who must not
  divide by a speed near zero), no Mx, My, loaded radius or contact patch;
* transient slip by the relaxation length (:func:`relax`): the slip that acts is a first
  order lag of the kinematic slip, d(alpha')/ds = (alpha - alpha') / sigma_y over the
  travelled distance s (Pacejka Sec. 7.2, Eq. 7.8; the same for kappa with sigma_x).

Checked against MFeval (Marco Furlan's open MATLAB implementation of MF 5.2/6.1/6.2, matched
by its author to TNO's MF-Tyre), run under GNU Octave, on the shipped
``tyres/mpv_215_65r16.tir``: 98 points within 1.3e-7 (tests/roads/test_magic_formula.py,
docs/tyres.md).

The ``.tir`` file (MF-Tyre / ADAMS "TeimOrbit" format, :func:`read_tir`) is sections
``[NAME]`` of ``KEY = VALUE`` lines; ``$`` and ``!`` start a comment (to the end of the line), a
string value is quoted (``'LEFT'``), a number may carry an exponent (``2.5E-4``). Keys are
case-insensitive and returned upper case, each twice: as ``KEY`` (the first one of that name:
the Magic Formula's coefficients are unique across sections) and as ``SECTION/KEY``
(``UNITS/MASS`` = 'kg' beside ``INERTIA/MASS`` = 11.0, the one name standard files use in two
sections). ``[SHAPE]`` tables (lines of bare numbers) are skipped. Errors name the file and
the line (:class:`cosim.errors.InputFileError`, exit 2).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from cosim.errors import InputFileError
from cosim.safe_open import read_user_file

_LINE = re.compile(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\s*=\s*(.*?)\s*$")


def _strip_comment(line: str) -> str:
    """``line`` without a ``$`` / ``!`` comment (outside quotes)."""
    quoted = False
    for i, ch in enumerate(line):
        if ch == "'":
            quoted = not quoted
        elif ch in "$!" and not quoted:
            return line[:i]
    return line


def parse_tir(text: str, source: str = "<tir>") -> dict[str, float | str]:
    """The ``KEY = VALUE`` pairs of a .tir text: numbers as ``float``, quoted strings as
    ``str`` (without the quotes). A key given twice in one section is an error (which one
    would win?)."""
    out: dict[str, float | str] = {}
    section = ""
    for n, raw in enumerate(text.splitlines(), 1):
        line = _strip_comment(raw).strip()
        if not line:
            continue
        if line.startswith("["):
            if not line.endswith("]"):
                raise InputFileError(source, f"section header without ']': {raw.strip()!r}", n)
            section = line[1:-1].strip().upper()
            continue
        m = _LINE.match(line)
        if m is None:
            if section == "SHAPE" or section.endswith("_TABLE") or line[0] in "{-+.0123456789":
                continue  # a table's rows
            raise InputFileError(source, f"expected KEY = VALUE, got {raw.strip()!r}", n)
        key, value = m.group(1).upper(), m.group(2)
        qualified = f"{section}/{key}"
        if qualified in out:
            raise InputFileError(source, f"key {key} given twice in [{section}]", n)
        parsed: float | str
        if value.startswith("'"):
            if not value.endswith("'") or len(value) < 2:
                raise InputFileError(source, f"{key}: unterminated string {value!r}", n)
            parsed = value[1:-1].strip()
        else:
            try:
                parsed = float(value)
            except ValueError:
                raise InputFileError(source, f"{key}: expected a number or a quoted string, "
                                             f"got {value!r}", n) from None
            if not math.isfinite(parsed):  # a NaN passed check and killed the run at step 0
                raise InputFileError(source, f"{key}: {value!r} is not a finite number", n)
        out[qualified] = parsed
        out.setdefault(key, parsed)
    return out


def read_tir(path: str | Path) -> dict[str, float | str]:
    """:func:`parse_tir` of the file ``path``."""
    p = Path(path)
    data = read_user_file(p, "tir", "tyre.tir")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:  # many .tir files are Latin-1 (a degree sign in a comment)
        text = data.decode("latin-1")
    return parse_tir(text, str(p))


EPS = 1e-6
"""The epsilons of Pacejka's divisions (epsilon_x, epsilon_y, epsilon_K of Eq. 4.E13 etc.)."""

A_MU = 10.0
"""Eq. 4.E8: the decay of the friction's scaling with the slip speed (A_mu = 10)."""

BUILTIN = Path(__file__).resolve().parent / "tyres" / "mpv_215_65r16.tir"
"""The shipped .tir: a 215/65 R16 tyre of the MPV (docs/tyres.md)."""


@dataclass(frozen=True)
class MagicFormula:
    """The parameters of one MF 6.1 tyre, from a .tir file (:meth:`from_tir`)."""

    p: dict[str, float]
    source: str = ""

    @classmethod
    def from_tir(cls, path: str | Path = BUILTIN) -> MagicFormula:
        """Read a .tir file; its FITTYP must be 61 or 62 (MF 6.1 / 6.2: the same force and
        moment equations)."""
        raw = read_tir(path)
        fittyp = raw.get("FITTYP")
        if fittyp not in (61.0, 62.0):
            raise InputFileError(str(path), f"FITTYP = {fittyp!r}: only Magic Formula 6.1 / "
                                            "6.2 files (FITTYP = 61 or 62) are read")
        nums = {k: float(v) for k, v in raw.items() if isinstance(v, float)}
        for key in ("FNOMIN", "UNLOADED_RADIUS", "PCX1", "PDX1", "PKX1", "PCY1", "PDY1",
                    "PKY1", "PKY2", "QBZ1", "QCZ1", "QDZ1"):
            if key not in nums:
                raise InputFileError(str(path), f"no {key}: not a complete MF 6.1 file")
        for key in ("FNOMIN", "UNLOADED_RADIUS"):
            if not nums[key] > 0:
                raise InputFileError(str(path), f"{key} = {nums[key]:g}: expected > 0")
        return cls(nums, str(path))

    def get(self, key: str, default: float = 0.0) -> float:
        """A parameter; absent coefficients are 0 and absent scaling factors (L*) 1."""
        return self.p.get(key, 1.0 if key.startswith("L") and key != "LMUV" else default)

    def steady_state(self, Fz: Any, kappa: Any, alpha: Any, gamma: Any = 0.0,  # noqa: N803
                     Vx: Any = None, p: Any = None) -> dict[str, np.ndarray]:  # noqa: N803
        """Forces and moments in steady state (see the module docstring; arrays broadcast)."""
        return steady_state(self, Fz, kappa, alpha, gamma, Vx, p)


def _arg(b: Any, c: Any, e: Any, x: Any) -> np.ndarray:
    """C atan(B x - E (B x - atan(B x))): the Magic Formula is D sin of it, the weighting
    function of combined slip G cos of it (Eqs. 4.E56, 4.E64; divided by its value at the
    shift x = S_H it is 1 at zero slip), the pneumatic trail D cos of it (4.E33)."""
    bx = np.asarray(b) * x
    return np.asarray(c * np.arctan(bx - e * (bx - np.arctan(bx))))


def _clip(x: np.ndarray, m: MagicFormula, lo: str, hi: str) -> np.ndarray:
    low, high = m.p.get(lo), m.p.get(hi)
    return np.clip(x, low if low is not None else -np.inf, high if high is not None else np.inf)


def steady_state(m: MagicFormula, Fz: Any, kappa: Any, alpha: Any, gamma: Any = 0.0,  # noqa: N803, C901
                 Vx: Any = None, p: Any = None) -> dict[str, np.ndarray]:  # noqa: N803
    """MF 6.1 in steady state, turn slip off (Pacejka 2012 Eqs. 4.E1-4.E78, zeta_i = 1)."""
    g = m.get
    R0 = g("UNLOADED_RADIUS")  # noqa: N806
    Vx = np.asarray(g("LONGVL", 16.7) if Vx is None else Vx, dtype=float)  # noqa: N806
    Fz = _clip(np.asarray(Fz, dtype=float), m, "FZMIN", "FZMAX")  # noqa: N806
    Fz = np.where(np.asarray(Fz) > 0, Fz, 0.0)  # noqa: N806
    kappa = _clip(np.asarray(kappa, dtype=float), m, "KPUMIN", "KPUMAX")
    alpha = _clip(np.asarray(alpha, dtype=float), m, "ALPMIN", "ALPMAX")
    gamma = _clip(np.asarray(gamma, dtype=float), m, "CAMMIN", "CAMMAX")
    pres = np.asarray(g("INFLPRES", g("NOMPRES")) if p is None else p, dtype=float)
    pres = _clip(pres, m, "PRESMIN", "PRESMAX")
    sgn_vx = np.where(Vx < 0, -1.0, 1.0)

    # ---- basic variables (4.E1-4.E8): nominal load, increments, gamma*, alpha*
    Fz0p = g("FNOMIN") * g("LFZO")  # noqa: N806  Fz0' (4.E1)
    dfz = (Fz - Fz0p) / Fz0p  # 4.E2a
    nompres = g("NOMPRES", 1.0)
    dpi = (pres - nompres) / nompres if nompres > 0 else np.zeros_like(pres)  # 4.E2b
    # alpha* = alpha, gamma* = gamma: MF-Tyre's own convention, which .tir files are fitted
    # in (the book's alpha* = tan(alpha) sgn(Vx), gamma* = sin(gamma) of 4.E3-4.E4 are for
    # large angles and running backwards; MFeval's use mode x1x is the same as here)
    a_star = alpha
    g_star = gamma
    # slip speed effect on friction (4.E7) with LMUV (0 in most files: LMU* = LMU)
    vs = np.abs(Vx) * np.sqrt(kappa**2 + np.tan(alpha) ** 2)  # |Vs| ~ |Vc| slip
    v0 = g("LONGVL", 16.7)
    lmux_s = g("LMUX") / (1.0 + g("LMUV") * vs / v0)
    lmuy_s = g("LMUY") / (1.0 + g("LMUV") * vs / v0)
    lmux_p = A_MU * lmux_s / (1.0 + (A_MU - 1.0) * lmux_s)  # 4.E8
    lmuy_p = A_MU * lmuy_s / (1.0 + (A_MU - 1.0) * lmuy_s)

    # ---- pure longitudinal slip (4.E9-4.E18)
    SHx = (g("PHX1") + g("PHX2") * dfz) * g("LHX")  # noqa: N806
    kx = kappa + SHx
    Cx = g("PCX1") * g("LCX")  # noqa: N806
    mux = ((g("PDX1") + g("PDX2") * dfz) * (1 + g("PPX3") * dpi + g("PPX4") * dpi**2)
           * (1 - g("PDX3") * gamma**2) * lmux_s)  # gamma, not gamma*: Eq. 4.E13
    Dx = mux * Fz  # noqa: N806
    Ex = np.minimum((g("PEX1") + g("PEX2") * dfz + g("PEX3") * dfz**2)  # noqa: N806
                    * (1 - g("PEX4") * np.sign(kx)) * g("LEX"), 1.0)
    Kxk = (Fz * (g("PKX1") + g("PKX2") * dfz) * np.exp(g("PKX3") * dfz)  # noqa: N806
           * (1 + g("PPX1") * dpi + g("PPX2") * dpi**2) * g("LKX"))
    Bx = Kxk / (Cx * Dx + EPS)  # noqa: N806
    SVx = Fz * (g("PVX1") + g("PVX2") * dfz) * g("LVX") * lmux_p  # noqa: N806
    Fx0 = Dx * np.sin(_arg(Bx, Cx, Ex, kx)) + SVx  # noqa: N806

    # ---- pure lateral slip (4.E19-4.E30)
    Kya = (g("PKY1") * Fz0p * (1 + g("PPY1") * dpi) * (1 - g("PKY3") * np.abs(g_star))  # noqa: N806
           * np.sin(g("PKY4") * np.arctan(Fz / ((g("PKY2") + g("PKY5") * g_star**2)
                                               * (1 + g("PPY2") * dpi) * Fz0p)))
           * g("LKY"))
    SVyg = Fz * (g("PVY3") + g("PVY4") * dfz) * g_star * g("LKYC") * lmuy_p  # noqa: N806
    SVy = Fz * (g("PVY1") + g("PVY2") * dfz) * g("LVY") * lmuy_p + SVyg  # noqa: N806
    Kyg0 = Fz * (g("PKY6") + g("PKY7") * dfz) * (1 + g("PPY5") * dpi) * g("LKYC")  # noqa: N806
    kya_e = Kya + EPS * np.where(Kya < 0, -1.0, 1.0)  # Kya + eps_K, away from 0 (4.E39)
    SHy = (g("PHY1") + g("PHY2") * dfz) * g("LHY") + (Kyg0 * g_star - SVyg) / kya_e  # noqa: N806
    ay = a_star + SHy
    Cy = g("PCY1") * g("LCY")  # noqa: N806
    muy = ((g("PDY1") + g("PDY2") * dfz) * (1 + g("PPY3") * dpi + g("PPY4") * dpi**2)
           * (1 - g("PDY3") * g_star**2) * lmuy_s)
    Dy = muy * Fz  # noqa: N806
    Ey = np.minimum((g("PEY1") + g("PEY2") * dfz)  # noqa: N806
                    * (1 + g("PEY5") * g_star**2 - (g("PEY3") + g("PEY4") * g_star)
                       * np.sign(ay)) * g("LEY"), 1.0)
    By = Kya / (Cy * Dy + EPS)  # noqa: N806
    Fy0 = Dy * np.sin(_arg(By, Cy, Ey, ay)) + SVy  # noqa: N806

    # ---- pure aligning moment (4.E31-4.E49)
    SHt = g("QHZ1") + g("QHZ2") * dfz + (g("QHZ3") + g("QHZ4") * dfz) * g_star  # noqa: N806
    at = a_star + SHt
    SHf = SHy + SVy / kya_e  # noqa: N806
    ar = a_star + SHf
    # Bt and Dt as in the MF 6.1 paper (Besselink et al. 2010, Eqs. A58, A60; MF-Tyre's):
    # QBZ4 on gamma and QBZ5 on |gamma| (the book's 4.E40 has QBZ6, absent from .tir files),
    # QDZ3 on gamma itself (the book's 4.E43 has |gamma*|)
    Bt = ((g("QBZ1") + g("QBZ2") * dfz + g("QBZ3") * dfz**2)  # noqa: N806
          * (1 + g("QBZ4") * gamma + g("QBZ5") * np.abs(gamma)) * g("LKY") / lmuy_s)
    Ct = g("QCZ1")  # noqa: N806
    Dt0 = Fz * (R0 / Fz0p) * (g("QDZ1") + g("QDZ2") * dfz) * (1 - g("PPZ1") * dpi) \
        * g("LTR") * sgn_vx  # noqa: N806
    Dt = Dt0 * (1 + g("QDZ3") * gamma + g("QDZ4") * gamma**2)  # noqa: N806
    Et = np.minimum((g("QEZ1") + g("QEZ2") * dfz + g("QEZ3") * dfz**2)  # noqa: N806
                    * (1 + (g("QEZ4") + g("QEZ5") * g_star) * (2 / np.pi)
                       * np.arctan(Bt * Ct * at)), 1.0)
    Br = (g("QBZ9") * g("LKY") / lmuy_s + g("QBZ10") * By * Cy)  # noqa: N806
    Cr = 1.0  # noqa: N806  zeta_7 (no turn slip)
    Dr = (Fz * R0 * ((g("QDZ6") + g("QDZ7") * dfz) * g("LRES")  # noqa: N806
                     + ((g("QDZ8") + g("QDZ9") * dfz) * (1 + g("PPZ2") * dpi)
                        + (g("QDZ10") + g("QDZ11") * dfz) * np.abs(g_star))
                     * g_star * g("LKZC")) * lmuy_s * sgn_vx * np.cos(alpha))
    cos_a = np.cos(alpha)

    def trail(a: np.ndarray) -> np.ndarray:  # 4.E33 / 4.E73: t(alpha_t) with cos(alpha)
        return Dt * np.cos(_arg(Bt, Ct, Et, a)) * cos_a

    t0 = trail(at)
    Mzr0 = Dr * np.cos(Cr * np.arctan(Br * ar))  # noqa: N806
    Mz0 = -t0 * Fy0 + Mzr0  # noqa: N806

    # ---- combined slip: Fx (4.E50-4.E57)
    Bxa = ((g("RBX1") + g("RBX3") * g_star**2) * np.cos(np.arctan(g("RBX2") * kappa))  # noqa: N806
           * g("LXAL"))
    Cxa = g("RCX1")  # noqa: N806
    Exa = np.minimum(g("REX1") + g("REX2") * dfz, 1.0)  # noqa: N806
    SHxa = g("RHX1")  # noqa: N806
    a_s = a_star + SHxa
    Gxa = np.cos(_arg(Bxa, Cxa, Exa, a_s)) / np.cos(_arg(Bxa, Cxa, Exa, SHxa))  # noqa: N806
    Fx = Gxa * Fx0  # noqa: N806

    # ---- combined slip: Fy (4.E58-4.E67)
    DVyk = (muy * Fz * (g("RVY1") + g("RVY2") * dfz + g("RVY3") * g_star)  # noqa: N806
            * np.cos(np.arctan(g("RVY4") * a_star)))
    SVyk = DVyk * np.sin(g("RVY5") * np.arctan(g("RVY6") * kappa)) * g("LVYKA")  # noqa: N806
    SHyk = g("RHY1") + g("RHY2") * dfz  # noqa: N806
    ks = kappa + SHyk
    Byk = ((g("RBY1") + g("RBY4") * g_star**2)  # noqa: N806
           * np.cos(np.arctan(g("RBY2") * (a_star - g("RBY3")))) * g("LYKA"))
    Cyk = g("RCY1")  # noqa: N806
    Eyk = np.minimum(g("REY1") + g("REY2") * dfz, 1.0)  # noqa: N806

    Gyk = np.cos(_arg(Byk, Cyk, Eyk, ks)) / np.cos(_arg(Byk, Cyk, Eyk, SHyk))  # noqa: N806
    Fy = Gyk * Fy0 + SVyk  # noqa: N806

    # ---- combined slip: Mz (4.E71-4.E78). The equivalent slip angles and the arm s of Fx are
    # those of the MF 6.1 paper (Besselink, Schmeitz & Pacejka 2010, Vehicle System Dynamics
    # 48 S1, Eqs. A54-A56; what MF-Tyre computes), not the book's 4.E76-4.E78: tan() in the
    # root, and s on the rated load FNOMIN. The trail is scaled by LFZO as MF-Tyre does.
    ratio = (Kxk / kya_e) ** 2 * kappa**2
    at_eq = np.arctan(np.sqrt(np.tan(at) ** 2 + ratio)) * np.sign(at)  # A55
    ar_eq = np.arctan(np.sqrt(np.tan(ar) ** 2 + ratio)) * np.sign(ar)  # A54
    s = R0 * (g("SSZ1") + g("SSZ2") * (Fy / g("FNOMIN"))  # A56
              + (g("SSZ3") + g("SSZ4") * dfz) * gamma) * g("LS")
    t = trail(at_eq) * g("LFZO")
    Mzr = Dr * np.cos(Cr * np.arctan(Br * ar_eq))  # noqa: N806
    # Fy' of 4.E74: the side force of the same slip at zero camber, without the kappa-induced
    # SVyk (the trail acts on the force the slip angle makes, not on the camber thrust)
    if np.any(g_star != 0):
        zero = steady_state(m, Fz, kappa, alpha, 0.0, Vx, pres)
        Fy_p = zero["Fy"] - zero["SVyk"]  # noqa: N806
    else:
        Fy_p = Fy - SVyk  # noqa: N806
    Mz = -t * Fy_p + Mzr + s * Fx  # noqa: N806

    # ---- relaxation lengths (MF 6.1: sigma = slip stiffness / overall carcass stiffness)
    Cx_c = g("LONGITUDINAL_STIFFNESS") * (1 + g("PCFX1") * dfz + g("PCFX2") * dfz**2) \
        * (1 + g("PCFX3") * dpi)  # noqa: N806
    Cy_c = g("LATERAL_STIFFNESS") * (1 + g("PCFY1") * dfz + g("PCFY2") * dfz**2) \
        * (1 + g("PCFY3") * dpi)  # noqa: N806
    with np.errstate(divide="ignore", invalid="ignore"):
        sigma_x = np.where(Cx_c > 0, np.abs(Kxk) / Cx_c, np.nan)
        sigma_y = np.where(Cy_c > 0, np.abs(Kya) / Cy_c, np.nan)
    return {"Fx": Fx, "Fy": Fy, "Mz": Mz, "Fx0": Fx0, "Fy0": Fy0, "Mz0": Mz0, "Kxk": Kxk,
            "Kya": Kya, "mux": mux, "muy": muy, "t": t, "Mzr": Mzr, "s": s, "SVyk": SVyk,
            "sigma_x": sigma_x, "sigma_y": sigma_y, "Fz": Fz}


def relax(slip_prev: Any, slip: Any, Vx: Any, sigma: Any, dt: float) -> np.ndarray:  # noqa: N803
    """One step of transient slip: the slip that acts after ``dt`` [s], a first-order lag of
    the kinematic slip over the travelled distance ds = |Vx| dt with relaxation length
    ``sigma`` [m] (Pacejka 2012 Eq. 7.8: sigma d(alpha')/ds + alpha' = alpha), solved exactly
    for a slip held over the step: alpha' + (alpha - alpha')(1 - exp(-ds / sigma))."""
    ds = np.abs(np.asarray(Vx, dtype=float)) * dt
    sig = np.asarray(sigma, dtype=float)
    w = 1.0 - np.exp(-ds / np.where(sig > 0, sig, np.inf))
    prev = np.asarray(slip_prev, dtype=float)
    return prev + (np.asarray(slip, dtype=float) - prev) * np.where(sig > 0, w, 1.0)
