"""3-D solid FE model of the lower arm (scikit-fem), unit-load cases and natural frequencies.

Elements: 27-node triquadratic bricks (``ElementHex2``; the thesis used 20-node quadratic
bricks in ANSYS), linear elastic isotropic steel. The mesh is a mapped (structured) hex mesh of
the plate-like arm: an annulus between the outer outline and the lightening hole, with
``n_around`` x ``n_across`` elements in plane and ``n_thick`` through the thickness.

Nodes for fatigue are the scalar ``ElementHex2`` nodes (vertices, mid-edge, mid-face and
centre nodes, as the thesis's quadratic elements had mid-side nodes). Nodal stresses are the
element stresses evaluated at each node and averaged over the elements sharing it.

A joint load is applied to the patch of nodes within a radius (in the arm plane) of the
hardpoint, through all the thickness, distributed with the least-norm set of nodal forces whose
resultant is the unit force (or moment) at the hardpoint (an RBE3-like spider; the thesis used
stiff spider beams to hole-centre nodes). Supports: the body-bush patches are clamped.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.spatial import ConvexHull
from skfem import Basis, ElementHex2, ElementVector, MeshHex
from skfem.models.elasticity import lame_parameters

from . import arm_geometry as geo

#: stress component order (thesis Eq 6.1-6.6)
COMPONENTS = ("sx", "sy", "sz", "sxy", "syz", "szx")


# ---------------------------------------------------------------------------- geometry / mesh
def hull_outline(centres: np.ndarray, radii: Sequence[float],
                 n_per_circle: int = 720) -> np.ndarray:
    """Counter-clockwise polygon (m, 2) of the convex hull of circles (m)."""
    a = np.linspace(0.0, 2 * np.pi, n_per_circle, endpoint=False)
    pts = np.vstack([np.c_[cx + r * np.cos(a), cy + r * np.sin(a)]
                     for (cx, cy), r in zip(np.asarray(centres)[:, :2], radii, strict=True)])
    hull = ConvexHull(pts)
    return pts[hull.vertices]  # scipy gives 2-D hull vertices counter-clockwise


def _resample_closed(poly: np.ndarray, centre: np.ndarray, n: int,
                     theta0: float = -np.pi / 2) -> np.ndarray:
    """n points along a closed star-shaped polygon, counter-clockwise from the ray at theta0.

    Spacing blends equal angle about ``centre`` and equal arc length (both monotone), which
    keeps radial lines of the mapped mesh from skewing where the outline is far off-centre.
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


def annulus_hex_mesh(inner: np.ndarray, outer: np.ndarray, n_across: int, n_thick: int,
                     thickness: float) -> MeshHex:
    """Mapped hex mesh between two closed curves sampled at the same n points (m).

    Node (i, j, k): (1 - j/n_across) inner[i] + (j/n_across) outer[i], z from -h/2 to h/2.
    """
    n_s = inner.shape[0]
    base = MeshHex.init_tensor(np.arange(n_s + 1.0), np.arange(n_across + 1.0),
                               np.arange(n_thick + 1.0))
    ii, jj, kk = (np.rint(base.p[d]).astype(int) for d in range(3))
    ii_wrapped = ii % n_s
    key = (ii_wrapped * (n_across + 1) + jj) * (n_thick + 1) + kk
    uniq, new_index = np.unique(key, return_inverse=True)
    t = new_index[base.t]
    first = np.zeros(uniq.size, dtype=int)
    first[new_index] = np.arange(key.size)
    i, j, k = ii_wrapped[first], jj[first], kk[first]
    r = j / n_across
    xy = (1 - r)[:, None] * inner[i] + r[:, None] * outer[i]
    z = -0.5 * thickness + thickness * k / n_thick
    p = np.vstack([xy.T, z])
    # orientation: local vertex 0 -> 2 is +i, 0 -> 1 is +j, 0 -> 3 is +k
    e0 = t[:, 0]
    jac = np.stack([p[:, e0[2]] - p[:, e0[0]], p[:, e0[1]] - p[:, e0[0]],
                    p[:, e0[3]] - p[:, e0[0]]])
    if np.linalg.det(jac) < 0:
        p[2] = -p[2]
    return MeshHex(p, t)


def box_hex_mesh(lx: float, ly: float, lz: float, nx: int, ny: int, nz: int) -> MeshHex:
    """Prismatic bar [0, lx] x [-ly/2, ly/2] x [-lz/2, lz/2] (m), for checks."""
    return MeshHex.init_tensor(np.linspace(0, lx, nx + 1), np.linspace(-ly / 2, ly / 2, ny + 1),
                               np.linspace(-lz / 2, lz / 2, nz + 1))


def arm_mesh_divisions(mesh_size: float) -> tuple[int, int, int]:
    """(n_around, n_across, n_thick) of the default arm for a target element size (m)."""
    outer = hull_outline(np.array([geo.BUSH_FRONT, geo.BUSH_REAR, geo.BALL_JOINT]),
                         [geo.BUSH_BOSS_RADIUS, geo.BUSH_BOSS_RADIUS, geo.BALL_JOINT_BOSS_RADIUS])
    perim = float(np.sum(np.hypot(*np.diff(np.vstack([outer, outer[:1]]), axis=0).T)))
    n_around = max(16, int(np.ceil(perim / mesh_size / 4)) * 4)
    n_across = max(2, int(np.ceil(0.075 / mesh_size)))
    n_thick = max(1, int(np.ceil(geo.PLATE_THICKNESS / mesh_size)))
    return n_around, n_across, n_thick


def arm_mesh(mesh_size: float = 0.03) -> MeshHex:
    """Hex mesh of the default arm (`arm_geometry`) with quadratic elements of ~mesh_size (m)."""
    n_around, n_across, n_thick = arm_mesh_divisions(mesh_size)
    outer = hull_outline(np.array([geo.BUSH_FRONT, geo.BUSH_REAR, geo.BALL_JOINT]),
                         [geo.BUSH_BOSS_RADIUS, geo.BUSH_BOSS_RADIUS, geo.BALL_JOINT_BOSS_RADIUS])
    hole = hull_outline(geo.HOLE_CORNERS, [geo.HOLE_FILLET_RADIUS] * 3)
    centre = geo.HOLE_CORNERS.mean(axis=0)
    inner_pts = _resample_closed(hole, centre, n_around)
    outer_pts = _resample_closed(outer, centre, n_around)
    return annulus_hex_mesh(inner_pts, outer_pts, n_across, n_thick, geo.PLATE_THICKNESS)


# ---------------------------------------------------------------------------- the FE model
@dataclass
class LoadCase:
    """A unit load at a point: force (N) and moment (N m) vectors, on a node patch."""

    name: str
    point: np.ndarray
    radius: float
    force: np.ndarray
    moment: np.ndarray


class SolidModel:
    """Linear elastic 3-D solid on a hex mesh (SI: m, Pa, kg/m^3)."""

    def __init__(self, mesh: MeshHex, E: float, nu: float, rho: float) -> None:
        self.mesh, self.E, self.nu, self.rho = mesh, E, nu, rho
        self.elem = ElementHex2()
        self.vbasis = Basis(mesh, ElementVector(self.elem))
        self.sbasis = Basis(mesh, self.elem)
        self.lam, self.mu = lame_parameters(E, nu)
        self.node_xyz = self.sbasis.doflocs.T.copy()  # (n_nodes, 3)
        split = self.vbasis.split_indices()
        self.node_dofs = np.stack(split, axis=1)  # (n_nodes, 3) vector dofs of each node
        if not np.allclose(self.vbasis.doflocs[:, split[0]], self.sbasis.doflocs):
            raise RuntimeError("vector and scalar node numbering differ")  # pragma: no cover
        self.K = self._stiffness()

    def _element_dofs(self) -> np.ndarray:
        """(n_elems, 27 * 3) global vector dofs, ordered (local node, component)."""
        edofs = self.sbasis.element_dofs.T  # (n_elems, 27)
        return self.node_dofs[edofs].reshape(edofs.shape[0], -1)

    def _scatter(self, Ke: np.ndarray) -> sp.csr_matrix:
        gd = self._element_dofs()
        n = self.K_size
        rows = np.repeat(gd[:, :, None], gd.shape[1], axis=2)
        cols = np.repeat(gd[:, None, :], gd.shape[1], axis=1)
        return sp.coo_matrix((Ke.ravel(), (rows.ravel(), cols.ravel())), shape=(n, n)).tocsr()

    @property
    def K_size(self) -> int:
        return 3 * self.n_nodes

    def _stiffness(self) -> sp.csr_matrix:
        """Isotropic stiffness, vectorised over elements (the generic skfem form loops over
        the 81 x 81 local dof pairs in Python, which takes tens of seconds here):
        K_(ai)(bj) = ∫ λ ∂iNa ∂jNb + μ ∂jNa ∂iNb + μ δij ∇Na·∇Nb dV."""
        nloc = len(self.sbasis.basis)
        G = np.stack([self.sbasis.basis[a][0].grad for a in range(nloc)])  # (27, 3, e, q)
        dx = self.sbasis.dx  # (e, q)
        t1 = np.einsum("aieq,bjeq,eq->eaibj", G, G, dx, optimize=True)
        lap = np.einsum("akeq,bkeq,eq->eab", G, G, dx, optimize=True)
        Ke = self.lam * t1 + self.mu * t1.transpose(0, 1, 4, 3, 2)
        Ke += self.mu * lap[:, :, None, :, None] * np.eye(3)[None, None, :, None, :]
        return self._scatter(Ke.reshape(Ke.shape[0], 3 * nloc, 3 * nloc))

    @property
    def n_nodes(self) -> int:
        return self.node_xyz.shape[0]

    def surface_nodes(self) -> np.ndarray:
        """Boolean mask of the nodes on the free or loaded surface."""
        mask = np.zeros(self.n_nodes, dtype=bool)
        mask[self.sbasis.get_dofs().all()] = True
        return mask

    def patch(self, point: np.ndarray, radius: float) -> np.ndarray:
        """Nodes within ``radius`` (m) of ``point`` in the x-y plane (all thickness)."""
        d = np.hypot(self.node_xyz[:, 0] - point[0], self.node_xyz[:, 1] - point[1])
        idx = np.nonzero(d <= radius)[0]
        if idx.size < 3:
            raise ValueError(f"load/support patch at {point} has {idx.size} nodes; refine mesh")
        return idx

    def spider_forces(self, nodes: np.ndarray, point: np.ndarray, force: np.ndarray,
                      moment: np.ndarray) -> np.ndarray:
        """Least-norm nodal forces (n, 3): resultant ``force`` (N), ``moment`` (N m) at point."""
        r = self.node_xyz[nodes] - point
        n = nodes.size
        A = np.zeros((6, 3 * n))
        for a in range(3):
            A[a, a::3] = 1.0
        # (r × f)_x = ry fz - rz fy, (r × f)_y = rz fx - rx fz, (r × f)_z = rx fy - ry fx
        A[3, 2::3], A[3, 1::3] = r[:, 1], -r[:, 2]
        A[4, 0::3], A[4, 2::3] = r[:, 2], -r[:, 0]
        A[5, 1::3], A[5, 0::3] = r[:, 0], -r[:, 1]
        rhs = np.r_[force, moment]
        f = A.T @ np.linalg.lstsq(A @ A.T, rhs, rcond=None)[0]
        return f.reshape(n, 3)

    def load_vector(self, case: LoadCase) -> np.ndarray:
        nodes = self.patch(case.point, case.radius)
        f = self.spider_forces(nodes, case.point, case.force, case.moment)
        b = np.zeros(self.K.shape[0])
        b[self.node_dofs[nodes].ravel()] = f.ravel()
        return b

    def solve(self, cases: Sequence[LoadCase], fixed_nodes: np.ndarray) -> np.ndarray:
        """Static displacements (n_cases, n_dofs) with all dofs of ``fixed_nodes`` clamped."""
        fixed = self.node_dofs[fixed_nodes].ravel()
        free = np.setdiff1d(np.arange(self.K.shape[0]), fixed)
        B = np.stack([self.load_vector(c) for c in cases], axis=1)
        lu = spla.splu(self.K[free][:, free].tocsc())
        U = np.zeros((len(cases), self.K.shape[0]))
        U[:, free] = lu.solve(B[free]).T
        return U

    def nodal_stress(self, U: np.ndarray) -> np.ndarray:
        """Nodal-averaged stresses (n_cases, n_nodes, 6), Pa, of displacements (n_cases, n_dofs)."""
        X = self.elem.doflocs.T  # reference coordinates of the 27 local nodes
        qb = Basis(self.mesh, ElementVector(self.elem), quadrature=(X, np.ones(X.shape[1])))
        edofs = self.sbasis.element_dofs  # (27, n_elems): local node j <-> quadrature point j
        counts = np.bincount(edofs.ravel(), minlength=self.n_nodes).astype(float)
        out = np.zeros((U.shape[0], self.n_nodes, 6))
        for c in range(U.shape[0]):
            g = qb.interpolate(U[c]).grad  # (3, 3, n_elems, 27)
            eps = 0.5 * (g + g.transpose(1, 0, 2, 3))
            tr = eps[0, 0] + eps[1, 1] + eps[2, 2]
            comps = [
                2 * self.mu * eps[0, 0] + self.lam * tr,
                2 * self.mu * eps[1, 1] + self.lam * tr,
                2 * self.mu * eps[2, 2] + self.lam * tr,
                2 * self.mu * eps[0, 1],
                2 * self.mu * eps[1, 2],
                2 * self.mu * eps[2, 0],
            ]
            for k, s in enumerate(comps):
                # s is (n_elems, 27); edofs.T is (n_elems, 27)
                out[c, :, k] = np.bincount(edofs.T.ravel(), weights=s.ravel(),
                                           minlength=self.n_nodes) / counts
        return out

    def mass_matrix(self) -> sp.csr_matrix:
        """Consistent mass matrix, M_(ai)(bj) = δij ∫ ρ Na Nb dV."""
        nloc = len(self.sbasis.basis)
        N = np.stack([self.sbasis.basis[a][0].value for a in range(nloc)])  # (27, e, q)
        Me = self.rho * np.einsum("aeq,beq,eq->eab", N, N, self.sbasis.dx, optimize=True)
        Me = Me[:, :, None, :, None] * np.eye(3)[None, None, :, None, :]
        return self._scatter(Me.reshape(Me.shape[0], 3 * nloc, 3 * nloc))

    def volume(self) -> float:
        return float(np.sum(self.sbasis.dx))

    def natural_frequencies(self, n_flexible: int = 6) -> np.ndarray:
        """First free-free flexible natural frequencies (Hz); the 6 rigid-body modes dropped."""
        M = self.mass_matrix()
        shift = -(2 * np.pi * 5.0) ** 2  # K - σM positive definite for σ < 0
        vals = spla.eigsh(self.K, k=6 + n_flexible, M=M, sigma=shift, which="LM",
                          return_eigenvectors=False)
        omega2 = np.sort(np.maximum(vals, 0.0))
        return np.sqrt(omega2[6:]) / (2 * np.pi)
