"""Scalar equivalent stress per node from the six stress components (Pa).

Component order everywhere: σx, σy, σz, τxy, τyz, τzx (thesis Eq 6.1-6.6).

* ``signed_von_mises``: von Mises stress with the sign of the hydrostatic stress
  σh = (σx + σy + σz)/3 (positive when σh >= 0), so that tension and compression half-cycles
  are told apart in rainflow counting.
* ``abs_max_principal``: the principal stress of largest magnitude, with its sign
  (nCode's default for uniaxial surface stress; the thesis found the arm's cycles uniaxial).
"""

from __future__ import annotations

import numpy as np

EQUIVALENTS = ("signed_von_mises", "abs_max_principal")


def von_mises(s: np.ndarray) -> np.ndarray:
    """Von Mises stress of components ``s[..., 6]``."""
    sx, sy, sz, txy, tyz, tzx = (s[..., i] for i in range(6))
    return np.sqrt(
        0.5 * ((sx - sy) ** 2 + (sy - sz) ** 2 + (sz - sx) ** 2)
        + 3.0 * (txy**2 + tyz**2 + tzx**2)
    )


def signed_von_mises(s: np.ndarray) -> np.ndarray:
    """Von Mises stress signed by the hydrostatic stress (+ for σh >= 0)."""
    h = s[..., 0] + s[..., 1] + s[..., 2]
    return np.where(h >= 0.0, 1.0, -1.0) * von_mises(s)


def principal_extremes(s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Largest and smallest principal stresses (σ1, σ3) of ``s[..., 6]``.

    Closed-form eigenvalues of a symmetric 3x3 matrix (trigonometric solution of the
    characteristic cubic), vectorised over all leading axes.
    """
    sx, sy, sz, txy, tyz, tzx = (s[..., i] for i in range(6))
    q = (sx + sy + sz) / 3.0
    a, b, c = sx - q, sy - q, sz - q
    p1 = txy * txy + tyz * tyz + tzx * tzx
    p2 = a * a + b * b + c * c + 2.0 * p1
    p = np.sqrt(p2 / 6.0)
    det = a * b * c + 2.0 * txy * tyz * tzx - a * tyz * tyz - b * tzx * tzx - c * txy * txy
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(p > 0.0, det / (2.0 * p**3), 0.0)
    phi = np.arccos(np.clip(r, -1.0, 1.0)) / 3.0
    s1 = q + 2.0 * p * np.cos(phi)
    s3 = q + 2.0 * p * np.cos(phi + 2.0 * np.pi / 3.0)
    return s1, s3


def abs_max_principal(s: np.ndarray) -> np.ndarray:
    """Principal stress of largest magnitude, signed."""
    s1, s3 = principal_extremes(s)
    return np.where(np.abs(s1) >= np.abs(s3), s1, s3)


def equivalent(s: np.ndarray, kind: str) -> np.ndarray:
    """Equivalent stress of ``s[..., 6]`` by name (see `EQUIVALENTS`)."""
    if kind == "signed_von_mises":
        return signed_von_mises(s)
    if kind == "abs_max_principal":
        return abs_max_principal(s)
    raise ValueError(f"equivalent must be one of {EQUIVALENTS}, got {kind!r}")
