"""FE arm: closed-form beam, superposition vs direct solve, mesh convergence, modes."""

from __future__ import annotations

import numpy as np
import pytest

from cosim import lower_arm as geo
from nodes.fatigue.arm_fe import LoadCase, SolidModel, box_hex_mesh
from nodes.fatigue.arm_mesh import arm_mesh
from nodes.fatigue.influence import support_nodes
from nodes.fatigue.superposition import stress_history

E, NU, RHO = 200e9, 0.3, 7800.0


def _arm(ms):
    """The arm on its mesh with a 3-2-1 support (for the checks that need one)."""
    fe = SolidModel(arm_mesh(ms), E, NU, RHO)
    return fe, support_nodes(fe)


def test_cantilever_bending_stress_closed_form():
    L, b, h = 0.4, 0.04, 0.02
    fe = SolidModel(box_hex_mesh(L, b, h, 10, 2, 2), E, NU, RHO)
    fix = np.nonzero(np.isclose(fe.node_xyz[:, 0], 0.0))[0]
    U = fe.solve([LoadCase("tip", np.array([L, 0, 0]), 0.021, np.array([0, 0, 1.0]),
                           np.zeros(3))], fix)
    S = fe.nodal_stress(U)[0]
    i = np.nonzero(np.all(np.isclose(fe.node_xyz, [0.2, 0, h / 2]), axis=1))[0][0]
    # σx = -M c / I with M = F (L - x), c = h/2, I = b h³ / 12 (top fibre in compression)
    assert S[i, 0] == pytest.approx(-(L - 0.2) * (h / 2) / (b * h**3 / 12), rel=0.01)
    # tip deflection F L³ / (3 E I) (+ shear, small for L/h = 20)
    tip = np.nonzero(np.all(np.isclose(fe.node_xyz, [L, 0, 0]), axis=1))[0][0]
    w = U[0, fe.node_dofs[tip, 2]]
    assert w == pytest.approx(L**3 / (3 * E * b * h**3 / 12), rel=0.02)


def test_spider_load_resultant():
    fe, _ = _arm(0.03)
    nodes = fe.patch(geo.BALL_JOINT, geo.LOAD_PATCH_RADIUS)
    F, M = np.array([10.0, -20.0, 30.0]), np.array([1.0, 2.0, -3.0])
    f = fe.spider_forces(nodes, geo.BALL_JOINT, F, M)
    np.testing.assert_allclose(f.sum(axis=0), F, atol=1e-9)
    r = fe.node_xyz[nodes] - geo.BALL_JOINT
    np.testing.assert_allclose(np.cross(r, f).sum(axis=0), M, atol=1e-9)


def test_superposed_unit_cases_equal_direct_solution():
    fe, sup = _arm(0.03)
    cases = [LoadCase(f"{p}_{a}", geo.HARDPOINTS[p], geo.LOAD_PATCH_RADIUS, np.eye(3)[k],
                      np.zeros(3)) for p in ("ball_joint", "damper_mount")
             for k, a in enumerate("xyz")]
    C = fe.nodal_stress(fe.solve_free(cases, sup)[0])  # unit cases, inertia relief
    F = np.array([[350.0, -420.0, 3900.0, 0.0, 0.0, -6400.0]])
    combined = [LoadCase("bj", geo.BALL_JOINT, geo.LOAD_PATCH_RADIUS, F[0, :3], np.zeros(3)),
                LoadCase("dm", geo.DAMPER_MOUNT, geo.LOAD_PATCH_RADIUS, F[0, 3:], np.zeros(3))]
    U2 = fe.solve_free(combined, sup)[0]
    direct = fe.nodal_stress(U2.sum(axis=0, keepdims=True))[0]
    sup_stress = stress_history(F, C)[0]
    scale = np.abs(direct).max()
    np.testing.assert_allclose(sup_stress, direct, atol=1e-9 * scale)
    # one unit case scaled = FE solution at that load
    U3 = fe.solve_free([LoadCase("bz", geo.BALL_JOINT, geo.LOAD_PATCH_RADIUS,
                                 np.array([0, 0, 2500.0]), np.zeros(3))], sup)[0]
    np.testing.assert_allclose(stress_history(np.array([[0, 0, 2500.0, 0, 0, 0]]), C)[0],
                               fe.nodal_stress(U3)[0], atol=1e-9 * scale)


def test_a_mesh_too_coarse_for_the_load_patches_is_a_scenario_error_naming_the_key(
        monkeypatch, tmp_path):
    """A load patch with fewer than three nodes (here: a patch radius far below the element
    size) cannot carry a joint load: a ScenarioError naming the mesh key, exit code 2."""
    from cosim.errors import ScenarioError
    from nodes.fatigue.influence import builtin_influence
    from nodes.fatigue.material import steel_817M40

    monkeypatch.setattr(geo, "LOAD_PATCH_RADIUS", 1e-4)
    with pytest.raises(ScenarioError, match="fatigue.mesh_size_m") as err:
        builtin_influence(0.05, steel_817M40(), use_cache=False)
    assert err.value.exit_code == 2
