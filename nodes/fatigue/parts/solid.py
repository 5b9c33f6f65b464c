"""Solid FE of a part on quadratic tetrahedra (scikit-fem ``ElementTetP2``): joint couplings,
joint hardware masses, inertia relief, nodal stresses, free-free modes.

Reuses :class:`nodes.fatigue.arm_fe.SolidModel` (its 3-2-1 support, inertia relief, nodal
stress recovery and shift-invert eigen solver) and replaces the hex-specific parts:

* assembly in element chunks (the 30 x 30 element matrices of P2 tets, vectorised):
  stiffness with 4 Gauss points (exact: the strains of a straight-sided P2 tet are linear),
  consistent mass with 11 points (degree 4, exact);
* a joint's load enters through a **distributing coupling** (the least-norm nodal forces with
  the unit resultant at the joint centre: RBE3-like, as today's spider) on the joint's node
  set; ``rigid`` is refused until it is implemented (docs/parts.md);
* joint hardware (bush sleeves, the ball-joint cartridge) as point masses spread equally
  over the joint's nodes: in the mass matrix, so in the modes and the inertia relief.

Nodes (the P2 dofs: vertices and edge midpoints) carry the stresses; a node's stress is the
element stresses at the node averaged over its elements (as CalculiX does).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.sparse as sp
from skfem import Basis, ElementTetP2, ElementVector, MeshTet
from skfem.models.elasticity import lame_parameters

from ..arm_fe import SolidModel
from .mesh import TetMesh

DIRECT_MAX_DOFS = 400000
"""Up to this many dofs the static cases are solved by SuperLU (minimum-degree ordering) and
the modes' LOBPCG is preconditioned by SuperLU of K + σM; above it by AMG. Measured on the
arm's 30 mm mesh (75 936 free dofs, 2026-12-03, python -m bench arm-variant): SuperLU 40 s for the
factor (5.0e7 nonzeros in L + U, ~0.6 GB) and 1 s for all 15 cases, where AMG-CG took 42 s
per case (571 iterations: the 2-level aggregation hierarchy is weak on P2 tets), 650 s."""
SHIFT_INVERT_MAX_DOFS = 40000
LOBPCG_TOL = 1e-6
CHUNK = 20000
"""Elements assembled at a time (bounds the memory of the vectorised element matrices)."""
INT_K, INT_M = 2, 4


class PartFE(SolidModel):
    """Linear elastic P2-tet solid (m, Pa, kg/m^3) with point masses at joint nodes."""

    def __init__(self, mesh: TetMesh, E: float, nu: float, rho: float) -> None:
        self.tet = mesh
        self.mesh = MeshTet(mesh.p.T.copy(), mesh.t.T.copy())
        self.E, self.nu, self.rho = E, nu, rho
        self.elem = ElementTetP2()
        self.vbasis = Basis(self.mesh, ElementVector(self.elem), intorder=INT_K)
        self.sbasis = Basis(self.mesh, self.elem, intorder=INT_K)
        self.lam, self.mu = lame_parameters(E, nu)
        self.node_xyz = self.sbasis.doflocs.T.copy()
        split = self.vbasis.split_indices()
        self.node_dofs = np.stack(split, axis=1)
        self.point_mass = np.zeros(self.n_nodes)
        self.K = self._assemble(self._stiffness_chunk, self.sbasis)

    # ------------------------------------------------------------------ assembly
    def _assemble(self, kernel, basis: Basis) -> sp.csr_matrix:
        nloc = len(basis.basis)
        edofs = basis.element_dofs.T  # (e, 10)
        gd_all = self.node_dofs[edofs].reshape(edofs.shape[0], -1)  # (e, 30) (node, comp)
        n = self.K_size
        out = sp.csr_matrix((n, n))
        for s in range(0, edofs.shape[0], CHUNK):
            sl = slice(s, s + CHUNK)
            Ke = kernel(basis, sl, nloc)
            gd = gd_all[sl]
            rows = np.repeat(gd[:, :, None], gd.shape[1], axis=2)
            cols = np.repeat(gd[:, None, :], gd.shape[1], axis=1)
            out = out + sp.coo_matrix((Ke.ravel(), (rows.ravel(), cols.ravel())),
                                      shape=(n, n)).tocsr()
        return out

    def _stiffness_chunk(self, basis: Basis, sl: slice, nloc: int) -> np.ndarray:
        G = np.stack([basis.basis[a][0].grad[:, sl] for a in range(nloc)])  # (10, 3, e, q)
        dx = basis.dx[sl]
        t1 = np.einsum("aieq,bjeq,eq->eaibj", G, G, dx, optimize=True)
        lap = np.einsum("akeq,bkeq,eq->eab", G, G, dx, optimize=True)
        Ke = self.lam * t1 + self.mu * t1.transpose(0, 1, 4, 3, 2)
        Ke += self.mu * lap[:, :, None, :, None] * np.eye(3)[None, None, :, None, :]
        return Ke.reshape(Ke.shape[0], 3 * nloc, 3 * nloc)

    def _mass_chunk(self, basis: Basis, sl: slice, nloc: int) -> np.ndarray:
        N = np.stack([basis.basis[a][0].value[sl] for a in range(nloc)])  # (10, e, q)
        Me = self.rho * np.einsum("aeq,beq,eq->eab", N, N, basis.dx[sl], optimize=True)
        Me = Me[:, :, None, :, None] * np.eye(3)[None, None, :, None, :]
        return Me.reshape(Me.shape[0], 3 * nloc, 3 * nloc)

    def add_point_mass(self, nodes: np.ndarray, mass: float) -> None:
        """Hardware of ``mass`` [kg] spread equally over ``nodes`` (lumped)."""
        np.add.at(self.point_mass, nodes, mass / max(len(nodes), 1))
        for k in ("_M", "_massprops"):
            self.__dict__.pop(k, None)

    def mass_matrix(self) -> sp.csr_matrix:
        """Consistent mass of the solid plus the lumped joint hardware [kg]."""
        if "_M" not in self.__dict__:
            mb = Basis(self.mesh, self.elem, intorder=INT_M)
            M = self._assemble(self._mass_chunk, mb)
            d = np.zeros(self.K_size)
            for a in range(3):
                d[self.node_dofs[:, a]] = self.point_mass
            self._M = (M + sp.diags(d)).tocsr()
        return self._M

    def mass_properties(self) -> dict[str, np.ndarray | float]:
        """Mass [kg], centre of mass [m], inertia about it [kg m^2]: solid + hardware."""
        if "_massprops" not in self.__dict__:
            x = self.sbasis.global_coordinates().value.reshape(3, -1)
            dm = (self.rho * self.sbasis.dx).ravel()
            xs = np.hstack([x, self.node_xyz.T])
            ms = np.r_[dm, self.point_mass]
            m = float(ms.sum())
            com = (xs * ms).sum(axis=1) / m
            r = xs - com[:, None]
            r2 = (r * r).sum(axis=0)
            inertia = np.array([[(((r2 if i == j else 0.0) - r[i] * r[j]) * ms).sum()
                                 for j in range(3)] for i in range(3)])
            self._massprops = {"mass": m, "centre_of_mass": com, "inertia": inertia,
                               "solid_mass": float(dm.sum()),
                               "hardware_mass": float(self.point_mass.sum())}
        return self._massprops

    # ------------------------------------------------------------------ loads
    def coupling_load(self, nodes: np.ndarray, centre: np.ndarray, force: np.ndarray,
                      moment: np.ndarray) -> np.ndarray:
        """Load vector (n_dofs,) of a distributing coupling: the least-norm nodal forces on
        ``nodes`` whose resultant at ``centre`` is ``force`` [N] and ``moment`` [N m]."""
        f = self.spider_forces(nodes, np.asarray(centre, float), np.asarray(force, float),
                               np.asarray(moment, float))
        b = np.zeros(self.K_size)
        np.add.at(b, self.node_dofs[nodes].ravel(), f.ravel())
        return b

    def solve_loads(self, B: np.ndarray, support_nodes: Sequence[int],
                    method: str = "inertia_relief") -> tuple[np.ndarray, np.ndarray]:
        """Displacements (n_cases, n_dofs) of the free part under load vectors B (n_dofs,
        n_cases) on inertia relief (as arm_fe.SolidModel.solve_free), and the 3-2-1
        reactions (n_cases, 6) [N]."""
        fixed = self.three_two_one(support_nodes)
        if method == "inertia_relief":
            B = self.balanced_loads(B)
        elif method != "321":
            raise ValueError(f"supports must be 'inertia_relief' or '321', got {method!r}")
        free = np.setdiff1d(np.arange(self.K_size), fixed)
        Kff = self.K[free][:, free].tocsr()
        U = np.zeros((B.shape[1], self.K_size))
        U[:, free] = spd_solve(Kff, np.asarray(B[free]), self.rigid_body_modes()[free]).T
        reactions = (self.K[fixed] @ U.T).T - B[fixed].T
        return U, reactions

    def balanced_loads(self, B: np.ndarray) -> np.ndarray:
        """B less the rigid-body inertia forces it causes (inertia relief's balanced load)."""
        M = self.mass_matrix()
        phi = self.rigid_body_modes()
        MPhi = M @ phi
        return np.asarray(B - MPhi @ np.linalg.solve(phi.T @ MPhi, phi.T @ B))

    def modes(self, n_flexible: int = 6) -> tuple[np.ndarray, np.ndarray]:
        """First free-free flexible modes: frequencies [Hz] and shapes (n_dofs, n).

        Below ``SHIFT_INVERT_MAX_DOFS`` dofs shift-invert Lanczos with SuperLU; above it
        LOBPCG (residual 1e-6 of the problem scaled by K's and M's mean diagonals) in the
        M-orthogonal complement of the six rigid-body modes, preconditioned by SuperLU of
        K + σM (σ = (2π 100 Hz)²) up to ``DIRECT_MAX_DOFS`` and by smoothed-aggregation AMG
        of it above (LOBPCG with SuperLU there without pyamg)."""
        import importlib.util

        M = self.mass_matrix()
        phi = self.rigid_body_modes()
        amg = importlib.util.find_spec("pyamg") is not None
        if self.K_size > DIRECT_MAX_DOFS and amg:
            return self._modes_lobpcg(M, phi, n_flexible, direct=False)
        if self.K_size >= SHIFT_INVERT_MAX_DOFS:
            return self._modes_lobpcg(M, phi, n_flexible, direct=True)
        import scipy.sparse.linalg as spla

        from ..arm_fe import PERMC

        shift = -(2 * np.pi * 5.0) ** 2
        lu = spla.splu((self.K - shift * M).tocsc(), permc_spec=PERMC)
        op = spla.LinearOperator(self.K.shape, matvec=lu.solve, dtype=float)
        vals, vecs = spla.eigsh(self.K, k=6 + n_flexible, M=M, sigma=shift, which="LM",
                                OPinv=op)
        order = np.argsort(vals)
        vals, vecs = vals[order][6:], vecs[:, order][:, 6:]
        return np.sqrt(np.maximum(vals, 0.0)) / (2 * np.pi), vecs

    def _modes_lobpcg(self, M: sp.csr_matrix, phi: np.ndarray, n_flexible: int,
                      direct: bool) -> tuple[np.ndarray, np.ndarray]:
        """LOBPCG of the scaled problem, preconditioned by SuperLU (``direct``) or AMG of
        K + σM."""
        import scipy.sparse.linalg as spla

        # scaled so that the eigenvalues are O(1) and the residual tolerance is relative
        ks, ms = float(self.K.diagonal().mean()), float(M.diagonal().mean())
        Ks, Ms = (self.K / ks).tocsr(), (M / ms).tocsr()
        sigma = (2 * np.pi * 100.0) ** 2 * ms / ks
        A = (Ks + sigma * Ms).tocsr()
        if direct:
            from ..arm_fe import PERMC

            lu = spla.splu(A.tocsc(), permc_spec=PERMC)
            prec = spla.LinearOperator(A.shape, matvec=lu.solve, matmat=lu.solve,
                                       dtype=float)
        else:
            import pyamg  # type: ignore[import-untyped]

            ml = pyamg.smoothed_aggregation_solver(A, B=phi, symmetry="symmetric",
                                                   max_coarse=2000)
            prec = ml.aspreconditioner()
        rng = np.random.default_rng(0)
        X = rng.standard_normal((self.K_size, n_flexible + 4))
        vals, vecs = spla.lobpcg(Ks, X, B=Ms, M=prec, Y=phi,
                                 tol=LOBPCG_TOL, maxiter=300, largest=False)
        vals = vals * ks / ms
        order = np.argsort(vals)[:n_flexible]
        vals, vecs = vals[order], vecs[:, order]
        return np.sqrt(np.maximum(vals, 0.0)) / (2 * np.pi), vecs


def spd_solve(A: sp.csr_matrix, B: np.ndarray, near_null: np.ndarray) -> np.ndarray:
    """Solve A X = B (A symmetric positive definite; B (n, k)): conjugate gradients to a
    relative residual of 1e-11 preconditioned by smoothed-aggregation AMG (pyamg; the
    elasticity near-null space ``near_null``, the rigid-body modes, given), or SuperLU
    without pyamg."""
    import scipy.sparse.linalg as spla

    try:
        import pyamg  # type: ignore[import-untyped]
    except ImportError:
        pyamg = None
    if pyamg is None or A.shape[0] < DIRECT_MAX_DOFS:
        from ..arm_fe import PERMC

        lu = spla.splu(A.tocsc(), permc_spec=PERMC)
        return np.asarray(lu.solve(np.ascontiguousarray(B)))
    ml = pyamg.smoothed_aggregation_solver(A, B=near_null, symmetry="symmetric",
                                           max_coarse=2000)
    P = ml.aspreconditioner()
    X = np.zeros_like(B, dtype=float)
    for k in range(B.shape[1]):
        nb = np.linalg.norm(B[:, k])
        if nb == 0.0:
            continue
        x, info = spla.cg(A, B[:, k], rtol=1e-11, atol=0.0, M=P, maxiter=2000)
        if info != 0:
            raise RuntimeError(f"CG did not converge (case {k}, info {info})")
        X[:, k] = x
    return X
