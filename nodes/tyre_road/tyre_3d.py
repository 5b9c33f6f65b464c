"""The 3-D tyre of the four-corner vehicle: the Magic Formula's road-plane forces
from the wheel's kinematics, beside the vertical force of the point-contact tyre. Pure
numerics: no I/O (the tyre/road node calls it).

Per corner, from what the plant publishes (``FullVehicleDoubleWishbone.wheel_kinematics``,
the fields ``vx_wc``, ``vy_wc``, ``omega_w``, ``gamma``, ``r_l`` of ``plant/state``):

* slips (ISO-W, the .tir's axes): kappa = (omega r_l - V_x) / max(|V_x|, V_LOW), alpha =
  atan(V_y / max(|V_x|, V_LOW)) (from the wheel's x axis to the centre's velocity, about z
  up; F_y has the opposite sign, PKY1 < 0), inclination gamma;
* transient slip: first-order lags over the travelled distance with the MF 6.1 relaxation
  lengths sigma_x = K_xk / C_x, sigma_y = |K_ya| / C_y (:func:`.magic_formula.relax`, once
  per communication step h);
* F_z: the vertical tyre's F_t (point contact, W + k_t (z_g - z_w) >= 0, the thesis's);
* F_x, F_y, M_z: :func:`.magic_formula.steady_state` at (F_z, kappa', alpha', gamma, V_x),
  combined slip.

Effective rolling radius (ours; the thesis has none): the corner file's loaded radius r_l
(0.30 m built in), the plant's rolling radius (free rolling gives kappa = 0). A radial tyre's
R_e ~ R_0 - F_z / (3 k_z) (Pacejka 2012 Sec. 7.2.2: 0.34 m for the shipped .tir); a constant
R_e only shifts the free-rolling spin, not a manoeuvre's forces.

V_LOW = 1 m/s (ours): below it the slips' denominator is held (MF-Tyre's low-speed
treatment is not ported: magic_formula.py); the events run above 3 m/s.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cosim.config import ConfigReader

from .magic_formula import MagicFormula, relax, steady_state
from .tyres import PointContact

V_LOW = 1.0
"""The smallest |V_x| the slips divide by [m/s] (module docstring)."""


def kinematic_slip(kin: Mapping[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """(kappa [-], alpha [rad]) per corner from the wheel kinematics (module docstring)."""
    vx = np.asarray(kin["vx_wc"], dtype=float)
    vy = np.asarray(kin["vy_wc"], dtype=float)
    den = np.maximum(np.abs(vx), V_LOW)
    kappa = (np.asarray(kin["omega_w"], dtype=float) * np.asarray(kin["r_l"], dtype=float)
             - vx) / den
    return kappa, np.arctan(vy / den)


@dataclass
class Tyre3D:
    """The Magic Formula on every corner, with its transient slips as state."""

    mf: MagicFormula
    transient: bool = True
    kappa: np.ndarray | None = field(default=None, init=False)
    """The slips that act (after the relaxation), per corner."""
    alpha: np.ndarray | None = field(default=None, init=False)

    def forces(self, kin: Mapping[str, np.ndarray], F_z: np.ndarray,  # noqa: N803
               h: float) -> dict[str, np.ndarray]:
        """``Fx``, ``Fy`` [N] along the road-plane axes of the wheel (x forward in the wheel
        plane, y left), ``Mz`` [N m] about the road normal, and the slips ``kappa``,
        ``alpha`` that made them, the slip stiffnesses ``Kxk`` [N], ``Kya`` [N/rad] (for a
        Jacobian coupling), after a step of ``h`` [s] from the previous call."""
        kappa, alpha = kinematic_slip(kin)
        vx = np.asarray(kin["vx_wc"], dtype=float)
        gamma = np.asarray(kin["gamma"], dtype=float)
        Fz = np.maximum(np.asarray(F_z, dtype=float), 0.0)  # noqa: N806
        if self.transient:
            if self.kappa is None or self.alpha is None:  # start: steady state
                self.kappa, self.alpha = kappa, alpha
            else:
                sig = steady_state(self.mf, np.maximum(Fz, 1.0), self.kappa, self.alpha,
                                   gamma, np.abs(vx) + V_LOW)
                self.kappa = relax(self.kappa, kappa, vx, sig["sigma_x"], h)
                self.alpha = relax(self.alpha, alpha, vx, sig["sigma_y"], h)
            kappa, alpha = self.kappa, self.alpha
        out = steady_state(self.mf, Fz, kappa, alpha, gamma, np.maximum(np.abs(vx), V_LOW))
        return {"Fx": out["Fx"], "Fy": out["Fy"], "Mz": out["Mz"], "kappa": kappa,
                "alpha": alpha, "Kxk": out["Kxk"], "Kya": out["Kya"]}


MF_KEYS = ("model", "stiffness", "tir", "transient")
KIN_FIELDS = ("vx_wc", "vy_wc", "omega_w", "gamma", "x_wc", "y_wc", "r_l")
"""What the 3-D tyre and the road's path read of ``plant/state`` (the four-corner vehicle
publishes them)."""


def is_magic_formula(cfg: Mapping[str, Any]) -> bool:
    """Whether the ``[tyre]`` section asks for the Magic Formula tyre."""
    return cfg.get("model") == "magic_formula"


def build_tyre_3d(cfg: Mapping[str, Any], key_prefix: str = "tyre") -> tuple[PointContact,
                                                                              Tyre3D]:
    """``[tyre] model = "magic_formula"``: ``tir`` (a .tir file, MF 6.1/6.2; ``"builtin"``
    or absent: the shipped ``tyres/mpv_215_65r16.tir``), ``stiffness`` [N/m] of the vertical
    point contact (default the file's VERTICAL_STIFFNESS), ``transient`` (true: the
    relaxation lengths). Raises :class:`cosim.errors.ScenarioError` on a bad key or value,
    :class:`cosim.errors.InputFileError` on a bad file."""
    r = ConfigReader(cfg, key_prefix)
    r.only(MF_KEYS)
    path = r.string("tir", "builtin")
    mf = MagicFormula.from_tir() if path == "builtin" else MagicFormula.from_tir(path)
    k_file = mf.p.get("VERTICAL_STIFFNESS")  # the default, when the file has one > 0
    default = (k_file,) if k_file is not None and k_file > 0 else ()
    k_t = r.number("stiffness", *default, positive=True, unit="N/m")
    return PointContact(k_t=k_t), Tyre3D(mf, transient=r.boolean("transient", True))
