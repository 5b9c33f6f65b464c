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
stiff spider beams to hole-centre nodes).

Supports (:meth:`SolidModel.solve_free`), for a free part loaded at all its joints:

* ``inertia_relief`` (the thesis's, Ch 6.2, as ANSYS and Nastran do it): each load vector f is
  balanced by the rigid-body inertia forces it would cause, f_b = f - M Φ a with
  a = (Φᵀ M Φ)⁻¹ Φᵀ f (Φ: the six rigid-body modes, M: the consistent mass matrix), so Φᵀ f_b = 0;
  the balanced load is then solved on a statically determinate **3-2-1** set of six
  constraints, whose reactions are zero to rounding, so the stresses do not depend on which
  nodes carry them;
* ``321``: the unbalanced unit load on the 3-2-1 set alone. A single case's stresses then
  depend on the support nodes, but the superposition of a load set in equilibrium does not
  (the recorded joint loads are, up to the arm's own inertia and weight).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from skfem import Basis, ElementHex2, ElementVector, MeshHex
from skfem.models.elasticity import lame_parameters

INTORDER = 5
"""Quadrature: 3 x 3 x 3 Gauss points (exact to degree 5 per direction), the full integration
of 27-node bricks; scikit-fem's default for ElementHex2 uses 7 x 7 x 7 (12x the work)."""
PERMC = "MMD_AT_PLUS_A"
"""SuperLU column ordering: minimum degree on A^T + A suits the symmetric FE matrices (the
default COLAMD fills 7x more and factors ~40x slower on the arm)."""

#: stress component order (thesis Eq 6.1-6.6)
COMPONENTS = ("sx", "sy", "sz", "sxy", "syz", "szx")


def box_hex_mesh(lx: float, ly: float, lz: float, nx: int, ny: int, nz: int) -> MeshHex:
    """Prismatic bar [0, lx] x [-ly/2, ly/2] x [-lz/2, lz/2] (m), for checks."""
    return MeshHex.init_tensor(np.linspace(0, lx, nx + 1), np.linspace(-ly / 2, ly / 2, ny + 1),
                               np.linspace(-lz / 2, lz / 2, nz + 1))


# ---------------------------------------------------------------------------- the FE model
@dataclass
class LoadCase:
    """A unit load at a point: force (N) and moment (N m) vectors, on a node patch of
    ``radius`` (m) round the point. With ``points`` (k, 3) the load is divided equally among
    k patches instead (a joint modelled by several nodes, as the thesis split its revolute
    joints' loads over nodes A and B)."""

    name: str
    point: np.ndarray
    radius: float
    force: np.ndarray
    moment: np.ndarray
    points: np.ndarray | None = None


class SolidModel:
    """Linear elastic 3-D solid on a hex mesh (SI: m, Pa, kg/m^3)."""

    def __init__(self, mesh: MeshHex, E: float, nu: float, rho: float) -> None:
        self.mesh, self.E, self.nu, self.rho = mesh, E, nu, rho
        self.elem = ElementHex2()
        self.vbasis = Basis(mesh, ElementVector(self.elem), intorder=INTORDER)
        self.sbasis = Basis(mesh, self.elem, intorder=INTORDER)
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
        """Nodal force vector (n_dofs,) [N] of a load case."""
        points = [case.point] if case.points is None else list(case.points)
        b = np.zeros(self.K.shape[0])
        for pt in points:
            nodes = self.patch(pt, case.radius)
            f = self.spider_forces(nodes, pt, np.asarray(case.force) / len(points),
                                   np.asarray(case.moment) / len(points))
            np.add.at(b, self.node_dofs[nodes].ravel(), f.ravel())
        return b

    def solve(self, cases: Sequence[LoadCase], fixed_nodes: np.ndarray) -> np.ndarray:
        """Static displacements (n_cases, n_dofs) with all dofs of ``fixed_nodes`` clamped."""
        fixed = self.node_dofs[fixed_nodes].ravel()
        free = np.setdiff1d(np.arange(self.K.shape[0]), fixed)
        B = np.stack([self.load_vector(c) for c in cases], axis=1)
        lu = spla.splu(self.K[free][:, free].tocsc(), permc_spec=PERMC)
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

    # ------------------------------------------------------------- free part: supports
    def rigid_body_modes(self, about: np.ndarray | None = None) -> np.ndarray:
        """Φ (n_dofs, 6): unit translations x, y, z and unit rotations about x, y, z through
        ``about`` (default: the centre of mass) [m per m, m per rad]."""
        o = self.mass_properties()["centre_of_mass"] if about is None else np.asarray(about)
        r = self.node_xyz - o
        phi = np.zeros((self.K_size, 6))
        for a in range(3):
            phi[self.node_dofs[:, a], a] = 1.0
        # rotation e_k: u = e_k × r
        rot = [np.c_[np.zeros(len(r)), -r[:, 2], r[:, 1]], np.c_[r[:, 2], np.zeros(len(r)),
               -r[:, 0]], np.c_[-r[:, 1], r[:, 0], np.zeros(len(r))]]
        for k, u in enumerate(rot):
            for a in range(3):
                phi[self.node_dofs[:, a], 3 + k] = u[:, a]
        return phi

    def three_two_one(self, nodes: Sequence[int]) -> np.ndarray:
        """The dofs of a 3-2-1 support on three nodes A, B, C (not collinear): A all three
        translations, B the two axes least along AB, C the axis most normal to the plane
        ABC. Returns 6 global dof indices."""
        a, b, c = (int(n) for n in nodes)
        pa, pb, pc = self.node_xyz[[a, b, c]]
        ab = (pb - pa) / np.linalg.norm(pb - pa)
        nrm = np.cross(pb - pa, pc - pa)
        if np.linalg.norm(nrm) < 1e-9:
            raise ValueError("3-2-1 support nodes are collinear")
        nrm /= np.linalg.norm(nrm)
        b_axes = np.argsort(np.abs(ab))[:2]  # the two axes least along AB
        c_axis = int(np.argmax(np.abs(nrm)))
        dofs = [self.node_dofs[a, k] for k in range(3)]
        dofs += [self.node_dofs[b, k] for k in b_axes]
        dofs.append(self.node_dofs[c, c_axis])
        return np.asarray(dofs)

    def solve_free(self, cases: Sequence[LoadCase], support_nodes: Sequence[int],
                   method: str = "inertia_relief") -> tuple[np.ndarray, np.ndarray]:
        """Static displacements (n_cases, n_dofs) of the free part on a 3-2-1 support, and the
        support reactions (n_cases, 6) [N]; ``method`` "inertia_relief" or "321" (module
        docstring)."""
        fixed = self.three_two_one(support_nodes)
        B = np.stack([self.load_vector(c) for c in cases], axis=1)
        if method == "inertia_relief":
            M = self.mass_matrix()
            phi = self.rigid_body_modes()
            MPhi = M @ phi
            acc = np.linalg.solve(phi.T @ MPhi, phi.T @ B)  # (6, n_cases)
            B = B - MPhi @ acc
        elif method != "321":
            raise ValueError(f"supports must be 'inertia_relief' or '321', got {method!r}")
        free = np.setdiff1d(np.arange(self.K_size), fixed)
        lu = spla.splu(self.K[free][:, free].tocsc(), permc_spec=PERMC)
        U = np.zeros((len(cases), self.K_size))
        U[:, free] = lu.solve(B[free]).T
        reactions = (self.K[fixed] @ U.T).T - B[fixed].T
        return U, reactions

    def mass_properties(self) -> dict[str, np.ndarray | float]:
        """Mass [kg], centre of mass [m] and inertia tensor about it [kg m^2] of the mesh."""
        if not hasattr(self, "_massprops"):
            x = self.sbasis.global_coordinates().value  # (3, e, q)
            dm = self.rho * self.sbasis.dx
            m = float(dm.sum())
            com = np.array([(x[a] * dm).sum() for a in range(3)]) / m
            r = x - com[:, None, None]
            r2 = (r * r).sum(axis=0)
            inertia = np.array([[((r2 if i == j else 0.0) - r[i] * r[j]) * dm
                                 for j in range(3)] for i in range(3)])
            inertia = inertia.sum(axis=(2, 3))
            self._massprops = {"mass": m, "centre_of_mass": com, "inertia": inertia}
        return self._massprops

    def mass_matrix(self) -> sp.csr_matrix:
        """Consistent mass matrix, M_(ai)(bj) = δij ∫ ρ Na Nb dV."""
        if hasattr(self, "_M"):
            return self._M
        nloc = len(self.sbasis.basis)
        N = np.stack([self.sbasis.basis[a][0].value for a in range(nloc)])  # (27, e, q)
        Me = self.rho * np.einsum("aeq,beq,eq->eab", N, N, self.sbasis.dx, optimize=True)
        Me = Me[:, :, None, :, None] * np.eye(3)[None, None, :, None, :]
        self._M: sp.csr_matrix = self._scatter(Me.reshape(Me.shape[0], 3 * nloc, 3 * nloc))
        return self._M

    def volume(self) -> float:
        return float(np.sum(self.sbasis.dx))

    def natural_frequencies(self, n_flexible: int = 6) -> np.ndarray:
        """First free-free flexible natural frequencies (Hz); the 6 rigid-body modes dropped."""
        M = self.mass_matrix()
        shift = -(2 * np.pi * 5.0) ** 2  # K - σM positive definite for σ < 0
        lu = spla.splu((self.K - shift * M).tocsc(), permc_spec=PERMC)
        op = spla.LinearOperator(self.K.shape, matvec=lu.solve, dtype=float)
        vals = spla.eigsh(self.K, k=6 + n_flexible, M=M, sigma=shift, which="LM", OPinv=op,
                          return_eigenvectors=False)
        omega2 = np.sort(np.maximum(vals, 0.0))
        return np.sqrt(omega2[6:]) / (2 * np.pi)
