"""Test oracle: the hand-meshed forged lower arm this project had before the CAD arm.

Removed from the product on 2026-12-06 (issue #42: one arm path, nodes/fatigue/parts/; its
history in CHANGELOG.md). What is left is its geometry and mapped hex mesh, which is where
the plant's lower-arm mass properties (:data:`cosim.lower_arm.MASS_PROPERTIES`) came from:
tests/fatigue/test_arm_card.py recomputes them here.

The arm in plan is an annulus between its outer outline (the convex hull of round bosses at
the two bush eyes and the ball joint) and a rounded triangular lightening hole; in section an
H: a 3 mm web, ribs along the outer edge and round the hole (54 mm deep at the legs' roots,
tapering to 30 mm by the ball joint, 30 mm on the base member) and deep solid hubs at the
joints. The mesh is mapped: ``n_around`` points along both closed curves joined by straight
across lines, one element row per rib, a tapered transition row, the web divided evenly;
``n_thick`` layers through the local depth (symmetric about z = 0). Metres, arm frame.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.spatial import ConvexHull
from skfem import Basis, ElementHex1, MeshHex

from cosim.lower_arm import BALL_JOINT, BUMP_STOP_PAD, BUSH_FRONT, BUSH_REAR, DAMPER_MOUNT

BUSH_BOSS_RADIUS, BALL_JOINT_BOSS_RADIUS = 0.030, 0.032
HOLE_CORNERS = np.array([[0.079, 0.030], [-0.073, 0.030], [0.016, 0.192]])
HOLE_FILLET_RADIUS = 0.026
WEB_DEPTH = 0.003
RIB_DEPTH, RIB_DEPTH_TIP, RIB_TAPER_Y = 0.054, 0.030, (0.05, 0.28)
BASE_RIB_DEPTH, BASE_BLEND_Y, BASE_BLEND_X = 0.030, (0.03, 0.06), (0.05, 0.09)
OUTER_RIB_WIDTH, HOLE_RIB_WIDTH, TRANSITION_WIDTH = 0.006, 0.005, 0.004
BUSH_EYE_DEPTH, BALL_JOINT_BOSS_DEPTH = 0.060, 0.036
SEAT_RADIUS, SEAT_DEPTH = 0.012, 0.024
EYE_CORE_RADIUS, EYE_BLEND, BOSS_BLEND = 0.004, 0.026, 0.008


def boss_depth(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Depth of the bosses at plan points [m]: full out to a core radius, then a cosine blend."""
    out = np.zeros(np.broadcast(x, y).shape)
    for c, r, h, blend in ((BUSH_FRONT, EYE_CORE_RADIUS, BUSH_EYE_DEPTH, EYE_BLEND),
                           (BUSH_REAR, EYE_CORE_RADIUS, BUSH_EYE_DEPTH, EYE_BLEND),
                           (BALL_JOINT, EYE_CORE_RADIUS, BALL_JOINT_BOSS_DEPTH, BOSS_BLEND),
                           (DAMPER_MOUNT, SEAT_RADIUS, SEAT_DEPTH, BOSS_BLEND),
                           (BUMP_STOP_PAD, SEAT_RADIUS, SEAT_DEPTH, BOSS_BLEND)):
        u = np.clip((np.hypot(x - c[0], y - c[1]) - r) / blend, 0.0, 1.0)
        out = np.maximum(out, h * 0.5 * (1.0 + np.cos(math.pi * u)))
    return out


def _smoothstep(v: np.ndarray, lo: float, hi: float) -> np.ndarray:
    return np.asarray(0.5 * (1.0 - np.cos(math.pi * np.clip((v - lo) / (hi - lo), 0.0, 1.0))))


def rib_depth(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Depth of the ribs at plan points [m]: the legs' (tapering), the base member's shallower."""
    w = np.maximum(_smoothstep(y, *BASE_BLEND_Y), _smoothstep(np.abs(x), *BASE_BLEND_X))
    v = np.clip((y - RIB_TAPER_Y[0]) / (RIB_TAPER_Y[1] - RIB_TAPER_Y[0]), 0.0, 1.0)
    leg = RIB_DEPTH + (RIB_DEPTH_TIP - RIB_DEPTH) * v
    return np.asarray(BASE_RIB_DEPTH + (leg - BASE_RIB_DEPTH) * w)


def hull_outline(centres: np.ndarray, radii: Sequence[float], n: int = 720) -> np.ndarray:
    """Counter-clockwise polygon (m, 2) of the convex hull of circles."""
    a = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    pts = np.vstack([np.c_[cx + r * np.cos(a), cy + r * np.sin(a)]
                     for (cx, cy), r in zip(np.asarray(centres)[:, :2], radii, strict=True)])
    return np.asarray(pts[ConvexHull(pts).vertices])


def resample_closed(poly: np.ndarray, centre: np.ndarray, n: int,
                    theta0: float = -np.pi / 2) -> np.ndarray:
    """n points along a closed star-shaped polygon from the ray at theta0, spaced by the mean
    of equal angle about ``centre`` and equal arc length."""
    ang = np.unwrap(np.arctan2(poly[:, 1] - centre[1], poly[:, 0] - centre[0]))
    k0 = int(np.argmin(np.abs(((ang - theta0 + np.pi) % (2 * np.pi)) - np.pi)))
    p = np.roll(poly, -k0, axis=0)
    p = np.vstack([p, p[:1]])
    ang = np.unwrap(np.arctan2(p[:, 1] - centre[1], p[:, 0] - centre[0]))
    seg = np.hypot(*np.diff(p, axis=0).T)
    w = 0.5 * ((ang - ang[0]) / (ang[-1] - ang[0]) + np.r_[0.0, np.cumsum(seg)] / seg.sum())
    u = np.arange(n) / n
    return np.c_[np.interp(u, w, p[:, 0]), np.interp(u, w, p[:, 1])]


def outline() -> np.ndarray:
    return hull_outline(np.array([BUSH_FRONT, BUSH_REAR, BALL_JOINT]),
                        [BUSH_BOSS_RADIUS, BUSH_BOSS_RADIUS, BALL_JOINT_BOSS_RADIUS])


def hole() -> np.ndarray:
    return hull_outline(HOLE_CORNERS, [HOLE_FILLET_RADIUS] * 3)


def across_levels(width: np.ndarray, n_web: int) -> tuple[np.ndarray, np.ndarray]:
    """Node fractions (n_around, n_levels) along each across line and the rib levels."""
    w_h, w_o, t = HOLE_RIB_WIDTH, OUTER_RIB_WIDTH, TRANSITION_WIDTH
    fixed = w_h + w_o + 2 * t
    scale = np.minimum(1.0, 0.75 * width / fixed)[:, None]  # narrow: web >= 25 %
    web = width[:, None] - scale * fixed
    d = [np.zeros_like(width)[:, None], scale * w_h, scale * (w_h + t)]
    d += [scale * (w_h + t) + web * k / n_web for k in range(1, n_web)]
    d += [width[:, None] - scale * (w_o + t), width[:, None] - scale * w_o, width[:, None]]
    frac = np.hstack(d) / width[:, None]
    is_rib = np.zeros(frac.shape[1], dtype=bool)
    is_rib[[0, 1, -2, -1]] = True
    return frac, is_rib


def arm_mesh(mesh_size: float) -> MeshHex:
    """The mapped hex mesh of the arm with ~``mesh_size`` [m] in plan."""
    edge = outline()
    perim = float(np.sum(np.hypot(*np.diff(np.vstack([edge, edge[:1]]), axis=0).T)))
    n_s = max(24, int(np.ceil(perim / mesh_size / 4)) * 4)
    n_web = max(2, int(np.ceil(0.06 / mesh_size)))
    n_thick = max(2, int(np.ceil(RIB_DEPTH / mesh_size / 2.0)))
    centre = HOLE_CORNERS.mean(axis=0)
    inner, outer = resample_closed(hole(), centre, n_s), resample_closed(edge, centre, n_s)
    frac, is_rib = across_levels(np.hypot(*(outer - inner).T), n_web)
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
    depth = np.where(is_rib[j], rib_depth(xy[:, 0], xy[:, 1]), WEB_DEPTH)
    depth = np.maximum(depth, boss_depth(xy[:, 0], xy[:, 1]))
    p = np.vstack([xy.T, depth * (k / n_thick - 0.5)])
    e0 = t[:, 0]
    jac = np.stack([p[:, e0[2]] - p[:, e0[0]], p[:, e0[1]] - p[:, e0[0]],
                    p[:, e0[3]] - p[:, e0[0]]])
    if np.linalg.det(jac) < 0:
        p[2] = -p[2]
    return MeshHex(p, t)


def mass_properties(mesh: MeshHex, rho: float) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass [kg], centre of mass [m] and inertia tensor about it [kg m^2] of the mesh (3 x 3 x
    3 Gauss points per brick, as the hex FE integrated them)."""
    b = Basis(mesh, ElementHex1(), intorder=5)
    x = b.global_coordinates().value.reshape(3, -1)
    dm = (rho * b.dx).ravel()
    m = float(dm.sum())
    com = (x * dm).sum(axis=1) / m
    r = x - com[:, None]
    inertia = np.eye(3) * ((r * r).sum(axis=0) * dm).sum() - (r * dm) @ r.T
    return m, com, inertia
