"""Hex mesh of the forged lower arm (`cosim.lower_arm`): mapped, 27-node quadratic bricks.

The arm in plan is an annulus: between its outer outline (the convex hull of round bosses at
the two bush eyes and the ball joint) and a rounded triangular lightening hole. The mesh is
mapped (structured): ``n_around`` points along both closed curves (same angular parameter
about the hole's centre), joined by straight *across* lines; along each across line the nodes
sit at fixed distances from the two edges so that the rib round the hole (width
``HOLE_RIB_WIDTH``) and the rib along the outer edge (``OUTER_RIB_WIDTH``) are one element
row each, then a tapered transition row (the forging's fillet) down to the web, whose width is
divided evenly. Through the depth, ``n_thick`` layers span the local depth (symmetric about
z = 0): the rib depth on the rib rows, the web depth on the web rows, the boss depth
(`cosim.lower_arm.boss_depth`) wherever it is larger. So one mesh carries web, ribs and
bosses of an H-section forging without a free mesher; the element size sets ``n_around``,
the web divisions and ``n_thick`` (mesh convergence in tests/fatigue/test_arm_fe.py).

Why not a free (tetrahedral) mesher such as gmsh: this shape is a 2.5-D forging whose every
feature lies along the mapped lines (ribs follow the edges, bosses are depth fields), so the
structured hex mesh resolves it with quadratic bricks, is deterministic (the FE cache key is
the geometry) and needs no binary dependency on a bare CI machine.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.spatial import ConvexHull
from skfem import MeshHex

from cosim import lower_arm as arm

TRANSITION_WIDTH = 0.004
"""Width (in plan) of the tapered row between a rib and the web [m] (forging fillet)."""


def hull_outline(centres: np.ndarray, radii: Sequence[float],
                 n_per_circle: int = 720) -> np.ndarray:
    """Counter-clockwise polygon (m, 2) of the convex hull of circles (m)."""
    a = np.linspace(0.0, 2 * np.pi, n_per_circle, endpoint=False)
    pts = np.vstack([np.c_[cx + r * np.cos(a), cy + r * np.sin(a)]
                     for (cx, cy), r in zip(np.asarray(centres)[:, :2], radii, strict=True)])
    hull = ConvexHull(pts)
    return pts[hull.vertices]  # scipy gives 2-D hull vertices counter-clockwise


def resample_closed(poly: np.ndarray, centre: np.ndarray, n: int,
                    theta0: float = -np.pi / 2) -> np.ndarray:
    """n points along a closed star-shaped polygon, counter-clockwise from the ray at theta0.

    Spacing blends equal angle about ``centre`` and equal arc length (both monotone), which
    keeps the across lines of the mapped mesh from skewing where the outline is far off-centre.
    """
    ang = np.unwrap(np.arctan2(poly[:, 1] - centre[1], poly[:, 0] - centre[0]))
    k0 = int(np.argmin(np.abs(((ang - theta0 + np.pi) % (2 * np.pi)) - np.pi)))
    p = np.roll(poly, -k0, axis=0)
    p = np.vstack([p, p[:1]])
    ang = np.unwrap(np.arctan2(p[:, 1] - centre[1], p[:, 0] - centre[0]))
    af = (ang - ang[0]) / (ang[-1] - ang[0])
    seg = np.hypot(*np.diff(p, axis=0).T)
    lf = np.r_[0.0, np.cumsum(seg)] / seg.sum()
    w = 0.5 * (af + lf)
    u = np.arange(n) / n
    return np.c_[np.interp(u, w, p[:, 0]), np.interp(u, w, p[:, 1])]


def outline() -> np.ndarray:
    """The arm's outer outline in plan (m, 2), counter-clockwise."""
    return hull_outline(np.array([arm.BUSH_FRONT, arm.BUSH_REAR, arm.BALL_JOINT]),
                        [arm.BUSH_BOSS_RADIUS, arm.BUSH_BOSS_RADIUS,
                         arm.BALL_JOINT_BOSS_RADIUS])


def hole() -> np.ndarray:
    """The lightening hole's edge in plan (m, 2), counter-clockwise."""
    return hull_outline(arm.HOLE_CORNERS, [arm.HOLE_FILLET_RADIUS] * 3)


def across_levels(width: np.ndarray, n_web: int) -> tuple[np.ndarray, np.ndarray]:
    """Node distances from the hole edge along each across line, and the depth class per level.

    Args:
        width: (n_around,) length of each across line [m].
        n_web: element rows across the web.
    Returns:
        (fractions (n_around, n_levels) in [0, 1], is_rib (n_levels,) bool).
    """
    w_h, w_o, t = arm.HOLE_RIB_WIDTH, arm.OUTER_RIB_WIDTH, TRANSITION_WIDTH
    fixed = w_h + w_o + 2 * t
    # where the section is narrow, shrink ribs and transitions together (web >= 25 %)
    scale = np.minimum(1.0, 0.75 * width / fixed)[:, None]
    web = width[:, None] - scale * fixed
    d = [np.zeros_like(width)[:, None], scale * w_h, scale * (w_h + t)]
    for k in range(1, n_web):
        d.append(scale * (w_h + t) + web * k / n_web)
    d += [width[:, None] - scale * (w_o + t), width[:, None] - scale * w_o, width[:, None]]
    frac = np.hstack(d) / width[:, None]
    # levels: 0 hole edge, 1 rib|transition, 2 transition|web, ..., web|transition, rib, edge
    is_rib = np.zeros(frac.shape[1], dtype=bool)
    is_rib[[0, 1, -2, -1]] = True
    return frac, is_rib


def divisions(mesh_size: float) -> tuple[int, int, int]:
    """(n_around, n_web, n_thick) for a target element size [m]."""
    edge = outline()
    perim = float(np.sum(np.hypot(*np.diff(np.vstack([edge, edge[:1]]), axis=0).T)))
    n_around = max(24, int(np.ceil(perim / mesh_size / 4)) * 4)
    n_web = max(2, int(np.ceil(0.06 / mesh_size)))
    n_thick = max(2, int(np.ceil(arm.RIB_DEPTH / mesh_size / 2.0)))
    return n_around, n_web, n_thick


def arm_mesh(mesh_size: float = 0.012) -> MeshHex:
    """Hex mesh of the arm with ~``mesh_size`` [m] in plan (see module docstring)."""
    n_s, n_web, n_thick = divisions(mesh_size)
    centre = arm.HOLE_CORNERS.mean(axis=0)
    inner = resample_closed(hole(), centre, n_s)
    outer = resample_closed(outline(), centre, n_s)
    width = np.hypot(*(outer - inner).T)
    frac, is_rib = across_levels(width, n_web)
    n_lev = frac.shape[1]
    base = MeshHex.init_tensor(np.arange(n_s + 1.0), np.arange(float(n_lev)),
                               np.arange(n_thick + 1.0))
    ii, jj, kk = (np.rint(base.p[d]).astype(int) for d in range(3))
    ii = ii % n_s  # close the ring
    key = (ii * n_lev + jj) * (n_thick + 1) + kk
    uniq, new_index = np.unique(key, return_inverse=True)
    t = new_index[base.t]
    first = np.zeros(uniq.size, dtype=int)
    first[new_index] = np.arange(key.size)
    i, j, k = ii[first], jj[first], kk[first]
    r = frac[i, j]
    xy = (1 - r)[:, None] * inner[i] + r[:, None] * outer[i]
    depth = np.where(is_rib[j], arm.rib_depth(xy[:, 0], xy[:, 1]), arm.WEB_DEPTH)
    depth = np.maximum(depth, arm.boss_depth(xy[:, 0], xy[:, 1]))
    z = depth * (k / n_thick - 0.5)
    p = np.vstack([xy.T, z])
    e0 = t[:, 0]
    jac = np.stack([p[:, e0[2]] - p[:, e0[0]], p[:, e0[1]] - p[:, e0[0]],
                    p[:, e0[3]] - p[:, e0[0]]])
    if np.linalg.det(jac) < 0:
        p[2] = -p[2]
    return MeshHex(p, t)

