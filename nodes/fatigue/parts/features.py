"""Re-entrant (concave) edges of a CAD solid: where a fillet belongs and a hot spot must not be.

An edge is classified by the share of material on a small circle round its midpoint, in the
plane normal to the edge (radius ``delta``): about 1/4 on a square convex edge, 1/2 on a smooth
(tangent) one, about 3/4 on a square re-entrant one. An edge with share > ``SHARP_SHARE`` is a
**sharp re-entrant edge**: a notch whose elastic stress does not converge with mesh refinement
(Williams' corner singularity, σ ~ r^(λ-1) with λ ≈ 0.54 for a 270° corner), so no assessed hot
spot may sit on one. Works on any OCC volume (the built-in arm or a user's STEP).
"""

from __future__ import annotations

import numpy as np

SHARP_SHARE = 0.60
"""Material share above which an edge is re-entrant and not tangent (a 6 mm fillet's junctions
with its faces are tangent, share 0.5; a 90° notch 0.75; a 150° notch 0.58 is let pass, being
a mild kink that a mesh of a few mm resolves)."""
N_SAMPLES = 24
_ORDER = [i + j for j in (0, 1, 2) for i in (0, 12, 6, 18, 3, 15, 9, 21)]
"""Samples spread round the circle (each costs OCC ~4 ms), taken until one is outside; then the
outside arc is followed (its unsampled neighbours first): ~10 samples stop a non-sharp count."""


def edge_share(curve: int, volume: int, delta: float,
               above: float | None = None) -> tuple[float, np.ndarray]:
    """(material share on the circle round the edge's midpoint, midpoint xyz [m]). With
    ``above``: exact only where it exceeds ``above``; else the count stops once it cannot, and
    the share returned is its bound then, <= ``above`` (the classification is the same)."""
    from gmsh import model  # type: ignore[import-untyped]

    lo, hi = model.getParametrizationBounds(1, curve)
    u = 0.5 * (lo[0] + hi[0])
    p = np.asarray(model.getValue(1, curve, [u]))
    t = np.asarray(model.getDerivative(1, curve, [u]))
    nt = np.linalg.norm(t)
    if nt == 0.0:
        return 0.5, p
    t /= nt
    a = np.cross(t, [1.0, 0.0, 0.0] if abs(t[0]) < 0.9 else [0.0, 1.0, 0.0])
    a /= np.linalg.norm(a)
    b = np.cross(t, a)
    ang = np.linspace(0.0, 2 * np.pi, N_SAMPLES, endpoint=False)
    pts = p + delta * (np.cos(ang)[:, None] * a + np.sin(ang)[:, None] * b)
    seen, out = np.zeros(N_SAMPLES, bool), np.zeros(N_SAMPLES, bool)
    while not seen.all():  # the count is the same in any order: only where it stops differs
        arc = np.flatnonzero(~seen & (np.roll(out, 1) | np.roll(out, -1)))
        i = int(arc[0]) if arc.size else next(j for j in _ORDER if not seen[j])
        seen[i], out[i] = True, model.isInside(3, volume, list(pts[i])) <= 0
        if out[i] and above is not None and N_SAMPLES - out.sum() <= above * N_SAMPLES:
            break  # outside on more than 1 - above of the circle: its share cannot exceed above
    return (N_SAMPLES - int(out.sum())) / N_SAMPLES, p


def sharp_reentrant_edges(volume: int, delta: float = 0.5e-3,
                          share: float = SHARP_SHARE) -> list[dict]:
    """Every sharp re-entrant edge of ``volume``: [{"curve", "share", "midpoint_m",
    "points_m" (sampled along the edge, (k, 3))}]."""
    from gmsh import model  # type: ignore[import-untyped]

    out = []
    curves = {abs(c) for face in model.getBoundary([(3, volume)], combined=False,
                                                   oriented=False)
              for _, c in model.getBoundary([face], combined=False, oriented=False)}
    for c in sorted(curves):
        s, mid = edge_share(c, volume, delta, above=share)
        if s > share:
            lo, hi = model.getParametrizationBounds(1, c)
            us = np.linspace(lo[0], hi[0], 21)
            pts = np.asarray(model.getValue(1, c, list(us))).reshape(-1, 3)
            out.append({"curve": c, "share": s, "midpoint_m": mid.tolist(), "points_m": pts})
    return out
