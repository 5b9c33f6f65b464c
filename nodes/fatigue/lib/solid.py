"""Solid FE of a part on quadratic tetrahedra (scikit-fem ``ElementTetP2``): joint couplings,
joint hardware masses, inertia relief, nodal stresses, free-free modes.

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

Supports, for a free part loaded at all its joints (:meth:`PartFE.solve_loads`):

* ``inertia_relief`` (the thesis's, Ch 6.2, as ANSYS and Nastran do it): each load vector f is
  balanced by the rigid-body inertia forces it would cause, f_b = f - M Φ a with
  a = (Φᵀ M Φ)⁻¹ Φᵀ f (Φ: the six rigid-body modes, M: the mass matrix), so Φᵀ f_b = 0; the
  balanced load is then solved on a statically determinate **3-2-1** set of six constraints,
  whose reactions are zero to rounding, so the stresses do not depend on which nodes carry them;
* ``321``: the unbalanced unit load on the 3-2-1 set alone. A single case's stresses then
  depend on the support nodes, but the superposition of a load set in equilibrium does not.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from skfem import Basis, ElementTetP2, ElementVector, MeshTet
from skfem.models.elasticity import lame_parameters

PERMC = "MMD_AT_PLUS_A"
"""SuperLU column ordering: minimum degree on A^T + A suits the symmetric FE matrices (the
default COLAMD fills 7x more and factors ~40x slower on an arm)."""

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


@dataclass
class TetMesh:
    """Linear tetrahedral mesh: p (n, 3) m, t (m, 4) vertex indices; labels (n,) of the
    input; node_sets name -> vertex indices; sharp_edges (k, 3) sample points [m] of the
    CAD's sharp re-entrant edges (empty without CAD)."""

    p: np.ndarray
    t: np.ndarray
    labels: np.ndarray
    node_sets: dict[str, np.ndarray] = field(default_factory=dict)
    sharp_edges: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    fillet_faces: int = 0
    source: str = ""


def _orient(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Tetrahedra with positive volume (swap two vertices of the inverted ones)."""
    a, b, c, d = (p[t[:, k]] for k in range(4))
    vol = np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a)
    t = t.copy()
    neg = vol < 0
    t[neg, 1], t[neg, 2] = t[neg, 2], t[neg, 1].copy()
    if np.any(np.abs(vol) < 1e-30):
        raise ValueError("degenerate tetrahedra (zero volume) in the mesh")
    return t


def compact_mesh(p: np.ndarray, t: np.ndarray, labels: np.ndarray,
             sets: dict[str, np.ndarray]) -> TetMesh:
    """Keep only the vertices the tetrahedra use, renumbered."""
    used = np.unique(t)
    new = -np.ones(p.shape[0], dtype=np.int64)
    new[used] = np.arange(used.size)
    out_sets = {k: new[v][new[v] >= 0] for k, v in sets.items()}
    return TetMesh(p[used], _orient(p[used], new[t]), labels[used], out_sets)



class PartFE:
    """Linear elastic P2-tet solid (m, Pa, kg/m^3) with point masses at joint nodes."""

    def __init__(self, mesh: TetMesh, E: float, nu: float, rho: float) -> None:
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

    @property
    def K_size(self) -> int:
        return 3 * self.n_nodes

    @property
    def n_nodes(self) -> int:
        return int(self.node_xyz.shape[0])

    def surface_nodes(self) -> np.ndarray:
        """Boolean mask of the nodes on the boundary."""
        mask = np.zeros(self.n_nodes, dtype=bool)
        mask[self.sbasis.get_dofs().all()] = True
        return mask

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
        f = A.T @ np.linalg.lstsq(A @ A.T, np.r_[force, moment], rcond=None)[0]
        return np.asarray(f.reshape(n, 3))

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
        n_cases) on inertia relief (or ``method = "321"``; module docstring), and the 3-2-1
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

    def nodal_stress(self, U: np.ndarray) -> np.ndarray:
        """Nodal-averaged stresses (n_cases, n_nodes, 6) [Pa], order xx, yy, zz, xy, yz, zx,
        of displacements (n_cases, n_dofs)."""
        X = self.elem.doflocs.T  # reference coordinates of the local nodes
        qb = Basis(self.mesh, ElementVector(self.elem), quadrature=(X, np.ones(X.shape[1])))
        edofs = self.sbasis.element_dofs  # (n_local, n_elems): local node j <-> point j
        counts = np.bincount(edofs.ravel(), minlength=self.n_nodes).astype(float)
        out = np.zeros((U.shape[0], self.n_nodes, 6))
        for c in range(U.shape[0]):
            g = qb.interpolate(U[c]).grad  # (3, 3, n_elems, n_local)
            eps = 0.5 * (g + g.transpose(1, 0, 2, 3))
            tr = eps[0, 0] + eps[1, 1] + eps[2, 2]
            mu2 = 2 * self.mu
            comps = [mu2 * eps[0, 0] + self.lam * tr, mu2 * eps[1, 1] + self.lam * tr,
                     mu2 * eps[2, 2] + self.lam * tr, mu2 * eps[0, 1], mu2 * eps[1, 2],
                     mu2 * eps[2, 0]]
            for k, s in enumerate(comps):
                out[c, :, k] = np.bincount(edofs.T.ravel(), weights=s.ravel(),
                                           minlength=self.n_nodes) / counts
        return out

    def rigid_body_modes(self, about: np.ndarray | None = None) -> np.ndarray:
        """Φ (n_dofs, 6): unit translations x, y, z and unit rotations about x, y, z through
        ``about`` (default: the centre of mass) [m per m, m per rad]."""
        o = self.mass_properties()["centre_of_mass"] if about is None else np.asarray(about)
        r = self.node_xyz - o
        phi = np.zeros((self.K_size, 6))
        for a in range(3):
            phi[self.node_dofs[:, a], a] = 1.0
        zero = np.zeros(len(r))  # rotation e_k: u = e_k × r
        rot = [np.c_[zero, -r[:, 2], r[:, 1]], np.c_[r[:, 2], zero, -r[:, 0]],
               np.c_[-r[:, 1], r[:, 0], zero]]
        for k, u in enumerate(rot):
            for a in range(3):
                phi[self.node_dofs[:, a], 3 + k] = u[:, a]
        return phi

    def three_two_one(self, nodes: Sequence[int]) -> np.ndarray:
        """The 6 global dofs of a 3-2-1 support on three nodes A, B, C (not collinear): A all
        three translations, B the two axes least along AB, C the axis most normal to ABC."""
        a, b, c = (int(n) for n in nodes)
        pa, pb, pc = self.node_xyz[[a, b, c]]
        ab = (pb - pa) / np.linalg.norm(pb - pa)
        nrm = np.cross(pb - pa, pc - pa)
        if np.linalg.norm(nrm) < 1e-9:
            raise ValueError("3-2-1 support nodes are collinear")
        dofs = [self.node_dofs[a, k] for k in range(3)]
        dofs += [self.node_dofs[b, k] for k in np.argsort(np.abs(ab))[:2]]
        dofs.append(self.node_dofs[c, int(np.argmax(np.abs(nrm)))])
        return np.asarray(dofs)

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
