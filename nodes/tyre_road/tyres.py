"""Vertical tyre models of thesis Ch. 3 Sec. 3.5.3: point contact (PC) and fixed footprint (FFP).

Both are linear springs without damping (the thesis neglects tyre damping) that cannot pull:
the force is saturated at zero when the wheel lifts off. Forces are **absolute**
(static + dynamic) and compressive-positive; displacements are from static equilibrium:

* PC (Fig. 3.15):  F_t = max(0, W + k_t (z_g - z_w))
* FFP (Fig. 3.16, Eq. 3.6, n = 4 in the thesis): n springs of k_t / n, each preloaded with W / n,
  spread over the contact length l_c and each seeing the road at its own position:
  F_t = sum_i max(0, W/n + (k_t/n)(z_g,i - z_w)). A step therefore reaches the springs one after
  the other as the tyre rolls over it at speed v (delay l_c / ((n - 1) v) between springs), and
  the force rises in n stages.

W [N] is the static tyre load (from the plant's ``static_tyre_load()``), z_w the wheel-centre
displacement [m], z_g the road height under the contact point(s) [m].
The saturation is per spring in the FFP (a spring over a pothole loses contact on its own);
the thesis saturates the sum, which is the same while every spring is in contact.

``k_eff`` = |dF_t / dz_w| [N/m] is returned for the plant node's coupling linearisation
(k_t, or k_t/n per spring in contact; 0 when lifted off).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def point_contact_force(z_w: np.ndarray | float, z_g: np.ndarray | float, k_t: float,
                        static_load: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """PC tyre: (F_t [N], k_eff [N/m]) per corner, F_t = max(0, W + k_t (z_g - z_w))."""
    f = np.asarray(static_load, dtype=float) + k_t * (np.asarray(z_g, dtype=float)
                                                      - np.asarray(z_w, dtype=float))
    in_contact = f > 0.0
    return np.where(in_contact, f, 0.0), np.where(in_contact, float(k_t), 0.0)


class Tyre:
    """A vertical tyre model: ``contact_offsets`` [m] are the longitudinal positions (x forward,
    relative to the wheel centre) where the road height is needed; :meth:`force` takes the road
    heights there, ``z_g`` of shape (..., n_points)."""

    contact_offsets: np.ndarray = np.zeros(1)
    k_t: float = 0.0

    def force(self, z_w: np.ndarray, z_g: np.ndarray,
              static_load: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError


@dataclass
class PointContact(Tyre):
    """Point-contact tyre of stiffness k_t [N/m] (thesis default for Ch. 4-6)."""

    k_t: float

    def __post_init__(self) -> None:
        self.contact_offsets = np.zeros(1)

    def force(self, z_w, z_g, static_load):
        z_g = np.asarray(z_g, dtype=float)
        return point_contact_force(z_w, z_g[..., 0], self.k_t, static_load)


@dataclass
class FixedFootprint(Tyre):
    """Fixed-footprint tyre: ``n`` springs of k_t/n over ``contact_length`` l_c [m].

    The springs sit at equal spacing from the leading edge (+l_c/2) to the trailing edge
    (-l_c/2) of the footprint (one spring at the centre when n = 1).
    """

    n: int
    contact_length: float
    k_t: float

    def __post_init__(self) -> None:
        if self.n < 1:
            raise ValueError(f"n must be >= 1, got {self.n}")
        if self.n == 1:
            self.contact_offsets = np.zeros(1)
        else:
            self.contact_offsets = np.linspace(0.5 * self.contact_length,
                                               -0.5 * self.contact_length, self.n)

    def force(self, z_w, z_g, static_load):
        """(F_t, k_eff) per corner; ``z_g`` has shape (..., n) in the order of the offsets."""
        z_g = np.asarray(z_g, dtype=float)
        z_w = np.asarray(z_w, dtype=float)[..., None]
        w = np.asarray(static_load, dtype=float)[..., None] / self.n
        k = self.k_t / self.n
        f_i = w + k * (z_g - z_w)
        contact = f_i > 0.0
        f = np.where(contact, f_i, 0.0).sum(axis=-1)
        return f, k * contact.sum(axis=-1).astype(float)
