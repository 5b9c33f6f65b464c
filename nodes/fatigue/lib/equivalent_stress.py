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
TILE_NODES = 256
"""Nodes per tile of :func:`equivalent_of` on a node-major block: its ~30 temporaries then
stay in cache (256 nodes x 64 samples x 8 B = 128 kB each); 2925 nodes at once were memory
bound, 1.9x slower on the Ch 6 arm (elementwise arithmetic: the same bits)."""


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
    characteristic cubic), vectorised over all leading axes. The components are first laid
    out one after the other (contiguous) and the arithmetic is done in place, term by term
    in the order of the formula (the same bits as the plain expression, about 2x faster).
    """
    s = np.asarray(s, dtype=float)
    shape = s.shape[:-1]
    s1, s3 = principal_extremes_of(np.ascontiguousarray(s.reshape(-1, 6).T))
    return s1.reshape(shape), s3.reshape(shape)


def invariants_of(comp: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(q, p, det) of components laid out first: q = σh the mean stress, p the deviator's
    scale sqrt(tr(s²)/6) and det its determinant (Pa, Pa, Pa³), the first half of
    :func:`principal_extremes_of` (shared, so both give these bits)."""
    sx, sy, sz, txy, tyz, tzx = comp
    q = sx + sy
    q += sz
    q /= 3.0
    a, b, c = sx - q, sy - q, sz - q
    t = np.empty_like(q)
    p1 = txy * txy
    p1 += np.multiply(tyz, tyz, out=t)
    p1 += np.multiply(tzx, tzx, out=t)
    p2 = a * a
    p2 += np.multiply(b, b, out=t)
    p2 += np.multiply(c, c, out=t)
    p1 *= 2.0
    p2 += p1
    p2 /= 6.0
    p = np.sqrt(p2, out=p2)
    det = a * b
    det *= c
    u = np.multiply(txy, 2.0)
    u *= tyz
    u *= tzx
    det += u
    det -= np.multiply(np.multiply(a, tyz, out=t), tyz, out=t)
    det -= np.multiply(np.multiply(b, tzx, out=t), tzx, out=t)
    det -= np.multiply(np.multiply(c, txy, out=t), txy, out=t)
    return q, p, det


def principal_extremes_of(comp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(σ1, σ3) of components laid out first, ``comp[6, ...]`` (each contiguous), the
    arithmetic of :func:`principal_extremes`."""
    q, p, det = invariants_of(comp)
    with np.errstate(divide="ignore", invalid="ignore"):
        den = p**3
        den *= 2.0
        r = np.divide(det, den, out=den)
    r[~(p > 0.0)] = 0.0
    np.clip(r, -1.0, 1.0, out=r)
    phi = np.arccos(r, out=r)
    phi /= 3.0
    two_p = np.multiply(p, 2.0, out=p)
    s1 = np.cos(phi)
    s1 *= two_p
    s1 += q
    phi += 2.0 * np.pi / 3.0
    s3 = np.cos(phi, out=phi)
    s3 *= two_p
    s3 += q
    return s1, s3


def abs_max_principal(s: np.ndarray) -> np.ndarray:
    """Principal stress of largest magnitude, signed."""
    s1, s3 = principal_extremes(s)
    return np.where(np.abs(s1) >= np.abs(s3), s1, s3)


def equivalent_of(comp: np.ndarray, kind: str) -> np.ndarray:
    """Equivalent stress of components laid out first, ``comp[6, ...]`` (the same values as
    :func:`equivalent` of the components laid out last).

    The arithmetic is elementwise, so its bits do not depend on the memory layout; a
    (6, n_samples, k) ``comp`` whose (6, k, n_samples) transpose is the contiguous one (as
    :func:`.superposition.superpose_components` gives) is computed in that order and the
    result handed back as its (n_samples, k) view, without a transposing copy."""
    if comp.ndim == 3 and comp.strides[2] > comp.strides[1]:
        ct = comp.transpose(0, 2, 1)  # (6, k, n)
        out = np.empty(ct.shape[1:])
        for j in range(0, ct.shape[1], TILE_NODES):
            out[j:j + TILE_NODES] = equivalent_of(ct[:, j:j + TILE_NODES], kind)
        return out.T
    if kind == "abs_max_principal":
        s1, s3 = principal_extremes_of(comp)
        return np.where(np.abs(s1) >= np.abs(s3), s1, s3)
    if kind == "signed_von_mises":
        return signed_von_mises(np.moveaxis(comp, 0, -1))
    raise ValueError(f"equivalent must be one of {EQUIVALENTS}, got {kind!r}")


def equivalent(s: np.ndarray, kind: str) -> np.ndarray:
    """Equivalent stress of ``s[..., 6]`` by name (see `EQUIVALENTS`)."""
    if kind == "signed_von_mises":
        return signed_von_mises(s)
    if kind == "abs_max_principal":
        return abs_max_principal(s)
    raise ValueError(f"equivalent must be one of {EQUIVALENTS}, got {kind!r}")
