"""The part FE (nodes/fatigue/lib/solid.py, P2 tetrahedra) on a bar: closed-form cantilever,
coupling resultant, superposition against a direct solve, inertia relief's supports."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse.linalg as spla
from skfem import MeshTet

from nodes.fatigue.lib.solid import PERMC, PartFE, TetMesh
from nodes.fatigue.lib.superposition import stress_history

E, NU, RHO = 200e9, 0.3, 7800.0
L, B, H = 0.4, 0.04, 0.02


@pytest.fixture(scope="module")
def bar() -> PartFE:
    """A steel bar [0, L] x [-B/2, B/2] x [-H/2, H/2] on 10 x 2 x 4 cubes of P2 tets."""
    m = MeshTet.init_tensor(np.linspace(0, L, 11), np.linspace(-B / 2, B / 2, 3),
                            np.linspace(-H / 2, H / 2, 5))
    return PartFE(TetMesh(m.p.T.copy(), m.t.T.copy(), np.arange(m.p.shape[1])), E, NU, RHO)


def _end(fe: PartFE, x: float) -> np.ndarray:
    return np.nonzero(np.isclose(fe.node_xyz[:, 0], x))[0]


def test_cantilever_bending_stress_closed_form(bar):
    fe = bar
    fixed = fe.node_dofs[_end(fe, 0.0)].ravel()
    free = np.setdiff1d(np.arange(fe.K_size), fixed)
    b = fe.coupling_load(_end(fe, L), np.array([L, 0, 0]), np.array([0, 0, 1.0]), np.zeros(3))
    U = np.zeros((1, fe.K_size))
    U[0, free] = spla.splu(fe.K[free][:, free].tocsc(), permc_spec=PERMC).solve(b[free])
    S = fe.nodal_stress(U)[0]
    top = np.isclose(fe.node_xyz[:, 0], 0.2) & np.isclose(fe.node_xyz[:, 2], H / 2)
    # σx = -M c / I with M = F (L - x), c = h/2, I = b h³ / 12 (top fibre in compression;
    # the mean over the fibre's nodes across the width)
    assert S[top, 0].mean() == pytest.approx(-(L - 0.2) * (H / 2) / (B * H**3 / 12), rel=0.02)
    # tip deflection F L³ / (3 E I) (+ shear, small for L/h = 20)
    tip = np.nonzero(np.all(np.isclose(fe.node_xyz, [L, 0, 0]), axis=1))[0][0]
    assert U[0, fe.node_dofs[tip, 2]] == pytest.approx(L**3 / (3 * E * B * H**3 / 12),
                                                       rel=0.02)


def test_coupling_load_resultant(bar):
    fe, p = bar, np.array([L, 0.0, 0.0])
    nodes = _end(bar, L)
    F, M = np.array([10.0, -20.0, 30.0]), np.array([1.0, 2.0, -3.0])
    f = fe.spider_forces(nodes, p, F, M)
    np.testing.assert_allclose(f.sum(axis=0), F, atol=1e-9)
    np.testing.assert_allclose(np.cross(fe.node_xyz[nodes] - p, f).sum(axis=0), M, atol=1e-9)


def _unit_cases(fe: PartFE) -> tuple[np.ndarray, list[tuple[np.ndarray, np.ndarray]]]:
    """Unit forces x, y, z at both ends (their node sets, centres): B (n_dofs, 6)."""
    joints = [(_end(fe, x), np.array([x, 0.0, 0.0])) for x in (0.0, L)]
    B = np.stack([fe.coupling_load(n, c, np.eye(3)[k], np.zeros(3)) for n, c in joints
                  for k in range(3)], axis=1)
    return B, joints


def test_superposed_unit_cases_equal_direct_solution(bar):
    fe = bar
    B, joints = _unit_cases(fe)
    sup = [0, int(np.argmax(fe.node_xyz[:, 0])), int(np.argmax(fe.node_xyz[:, 1]))]
    C = fe.nodal_stress(fe.solve_loads(B, sup)[0])  # unit cases, inertia relief
    F = np.array([[350.0, -420.0, 3900.0, 0.0, 0.0, -6400.0]])
    b = sum(fe.coupling_load(n, c, F[0, 3 * j:3 * j + 3], np.zeros(3))
            for j, (n, c) in enumerate(joints))
    direct = fe.nodal_stress(fe.solve_loads(b[:, None], sup)[0])[0]
    scale = np.abs(direct).max()
    np.testing.assert_allclose(stress_history(F, C)[0], direct, atol=1e-9 * scale)


def test_inertia_relief_reactions_vanish_and_stresses_do_not_depend_on_the_supports(bar):
    fe = bar
    B, _ = _unit_cases(fe)
    xyz = fe.node_xyz
    sup_a = [0, int(np.argmax(xyz[:, 0])), int(np.argmax(xyz[:, 1]))]
    sup_b = [int(np.argmax(xyz @ [1, 1, 1])), int(np.argmin(xyz @ [1, 1, 1])),
             int(np.argmax(xyz @ [0, -1, 1]))]
    (U1, R1), (U2, R2) = fe.solve_loads(B, sup_a), fe.solve_loads(B, sup_b)
    assert np.abs(R1).max() < 1e-6 and np.abs(R2).max() < 1e-6  # per 1 N case
    S1, S2 = fe.nodal_stress(U1), fe.nodal_stress(U2)
    assert np.abs(S1 - S2).max() < 1e-6 * np.abs(S1).max()
    # without inertia relief a single unbalanced case does depend on the supports
    V1 = fe.nodal_stress(fe.solve_loads(B[:, 2:3], sup_a, "321")[0])
    V2 = fe.nodal_stress(fe.solve_loads(B[:, 2:3], sup_b, "321")[0])
    assert np.abs(V1 - V2).max() > 0.1 * np.abs(V1).max()
