"""The forged lower arm's FE (issue #12): inertia relief, supports, mass, modes, the static
stresses under the plant's own loads, a hand calculation, mesh convergence, `suscosim arm`."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from cosim import lower_arm as geo
from nodes.fatigue.arm_fe import SolidModel
from nodes.fatigue.arm_mesh import arm_mesh
from nodes.fatigue.equivalent_stress import von_mises
from nodes.fatigue.influence import (
    BUILTIN_CASES,
    builtin_influence,
    joint_zone_nodes,
    support_nodes,
    unit_cases,
)
from nodes.fatigue.material import steel_817M40
from orchestrator.studies.arm_card import (
    fe_bending_stress,
    nominal_bending_stress,
    static_arm_loads,
)

MAT = steel_817M40()
MESH = 0.02  # the fatigue default


@pytest.fixture(scope="module")
def fe():
    return SolidModel(arm_mesh(0.03), MAT.E, MAT.nu, MAT.rho)


@pytest.fixture(scope="module")
def static_loads():
    return static_arm_loads()


def _other_supports(fe) -> list[int]:
    """A second 3-2-1 set, far from the default one: nodes nearest the damper seat, the
    bump-stop pad and the middle of the base member."""
    pts = [geo.DAMPER_MOUNT, geo.BUMP_STOP_PAD, np.array([0.0, -0.02, 0.0])]
    return [int(np.argmin(np.linalg.norm(fe.node_xyz - p, axis=1))) for p in pts]


def test_every_joint_load_is_a_unit_case_named_as_the_plant_publishes_it():
    from nodes.plant.double_wishbone import DoubleWishboneCorner

    corner = DoubleWishboneCorner()
    try:
        published = set(corner.loads()["arm"])
    finally:
        corner.close()
    assert set(BUILTIN_CASES) == published
    assert len(BUILTIN_CASES) == 15


def test_inertia_relief_reactions_vanish_and_stresses_do_not_depend_on_the_supports(fe):
    cases = unit_cases()
    U1, R1 = fe.solve_free(cases, support_nodes(fe))
    U2, R2 = fe.solve_free(cases, _other_supports(fe))
    assert np.abs(R1).max() < 1e-6 and np.abs(R2).max() < 1e-6  # per 1 N / 1 N m case
    S1, S2 = fe.nodal_stress(U1), fe.nodal_stress(U2)
    scale = np.abs(S1).max(axis=(1, 2), keepdims=True)
    assert np.abs(S1 - S2).max() < 1e-6 * scale.max()
    # without inertia relief a single unbalanced case does depend on the supports
    V1 = fe.nodal_stress(fe.solve_free(cases[:1], support_nodes(fe), "321")[0])
    V2 = fe.nodal_stress(fe.solve_free(cases[:1], _other_supports(fe), "321")[0])
    assert np.abs(V1 - V2).max() > 0.1 * np.abs(V1).max()


def _sim_loads(n_steps: int = 1600) -> list[dict[str, float]]:
    """The corner over a 60 mm 1-cos bump at 34 km/h (point-contact tyre, passive damper on the
    damper's velocity): the arm's joint loads at a few instants, incl. the peak."""
    from nodes.plant.double_wishbone import DoubleWishboneCorner

    corner = DoubleWishboneCorner()
    W, dt, v, out = corner.static_tyre_load(), 0.00025, 34 / 3.6, []
    try:
        for k in range(n_steps):
            s = k * dt * v - 1.0
            zg = 0.03 * (1 - np.cos(2 * np.pi * s / 0.8)) if 0 <= s <= 0.8 else 0.0
            st = corner.state()
            F_t = np.maximum(0.0, W + 239000.0 * (zg - st["z_w"]))
            corner.substep(dt, F_t, 3800.0 * st["v_damper"])
            if k % 100 == 99:
                out.append(dict(corner.loads()["arm"]))
    finally:
        corner.close()
    return out


def test_recorded_loads_are_nearly_balanced_so_321_and_inertia_relief_agree(fe, static_loads):
    """The joint loads the plant records balance each other up to the arm's own inertia and
    weight (5 kg at up to ~20 m/s^2 here: ~100 N against kN): a statically determinate 3-2-1
    support then reacts little, and its stresses equal those of inertia relief within 2 %
    with either support set (the ~100 N of unbalanced inertia enter the 3-2-1 set as point
    loads instead of being spread over the arm's mass)."""
    cases = unit_cases()
    C_ir = fe.nodal_stress(fe.solve_free(cases, support_nodes(fe))[0])
    U_a, R_a = fe.solve_free(cases, support_nodes(fe), "321")
    U_b, R_b = fe.solve_free(cases, _other_supports(fe), "321")
    C_a, C_b = fe.nodal_stress(U_a), fe.nodal_stress(U_b)
    assessed = fe.surface_nodes() & ~joint_zone_nodes(fe.node_xyz)
    samples = [static_loads] + _sim_loads()
    peak_bj = max(abs(s["ball_joint_z"]) for s in samples)
    assert peak_bj > 1.5 * abs(static_loads["ball_joint_z"])  # the bump loads the arm
    for loads in samples:
        f = np.array([loads[c.name] for c in cases])
        reaction = np.abs(f @ R_a)
        assert reaction.max() < 0.03 * peak_bj  # N against the event's peak joint load
        s_ir, s_a, s_b = (von_mises(np.einsum("c,cnk->nk", f, C))[assessed]
                          for C in (C_ir, C_a, C_b))
        top = s_ir.max()
        assert np.abs(s_a - s_ir).max() < 0.02 * top
        assert np.abs(s_b - s_ir).max() < 0.02 * top


def test_mass_and_mass_properties_agree_with_cosim_and_table_4_2():
    assert builtin_influence(MESH, MAT).meta["mass_kg"] == pytest.approx(geo.MASS_KG, rel=0.10)
    inf = builtin_influence(0.015, MAT)  # the mesh cosim.lower_arm.MASS_PROPERTIES came from
    mp = geo.MASS_PROPERTIES
    assert inf.meta["mass_kg"] == pytest.approx(geo.MASS_KG, rel=0.10)  # Table 4.2: 5 kg
    assert inf.meta["mass_kg"] == pytest.approx(mp["mass_kg"], rel=0.01)
    np.testing.assert_allclose(inf.meta["centre_of_mass_m"], mp["centre_of_mass_m"], atol=3e-3)
    np.testing.assert_allclose(np.diag(inf.meta["inertia_kg_m2"]),
                               np.diag(mp["inertia_kg_m2"]), rtol=0.02)


def test_first_flexible_mode_far_above_the_road_band():
    f = np.asarray(builtin_influence(MESH, MAT).meta["natural_frequencies_hz"])
    assert f.size == 6 and np.all(np.diff(f) >= 0)
    assert f[0] > 5 * 60.0  # quasi-static superposition valid (thesis: 0-60 Hz excitation)


def test_static_stresses_hand_calculation_and_3g_below_yield(static_loads):
    inf = builtin_influence(MESH, MAT)
    f = np.array([static_loads[c] for c in inf.case_names])
    vm = von_mises(np.einsum("c,cnk->nk", f, inf.coefficients))[inf.surface]
    hot = vm.max()
    assert 50e6 < hot < MAT.Sy / 3.0  # a 3 g bump (3 x the static set) stays below yield
    hand = nominal_bending_stress(static_loads)
    # the cut's moment is the outboard loads' (ball joint; the damper is idle at rest)
    assert hand["moment_nm"] == pytest.approx(
        (geo.BALL_JOINT[1] - hand["y_cut_m"]) * static_loads["ball_joint_z"], rel=1e-9)
    assert fe_bending_stress(inf, static_loads) == pytest.approx(hand["sigma_pa"], rel=0.15)


def test_mesh_convergence_at_the_hot_spot_and_the_legs(static_loads):
    """Static hot-spot von Mises and the legs' nominal bending stress at three element sizes:
    from 20 mm to 15 mm elements the hot spot (at the rear leg's root, by its eye) moves by
    less than 10 % and the nominal stress by less than 3 % (measured: 7.7 % and 1.3 %)."""
    hots, noms = [], []
    for ms in (0.025, 0.02, 0.015):
        inf = builtin_influence(ms, MAT)
        f = np.array([static_loads[c] for c in inf.case_names])
        vm = von_mises(np.einsum("c,cnk->nk", f, inf.coefficients))[inf.surface]
        hots.append(vm.max())
        noms.append(fe_bending_stress(inf, static_loads))
    assert abs(hots[2] - hots[1]) / hots[2] < 0.10
    assert abs(noms[2] - noms[1]) / abs(noms[2]) < 0.03
    assert abs(noms[1] - noms[0]) / abs(noms[2]) < 0.03


def test_arm_card_json():
    out = subprocess.run([sys.executable, "-m", "orchestrator.studies.arm_card", "--json"],
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    c = json.loads(out.stdout)
    for key in ("mass_kg", "modes_hz", "static_hotspot_stress_mpa", "static_hotspot_node",
                "static_hotspot_xyz_m", "max_stress_3g_mpa", "yield_mpa", "mesh_size_m",
                "n_nodes"):
        assert key in c
    assert len(c["modes_hz"]) == 6
    assert c["max_stress_3g_mpa"] == pytest.approx(3 * c["static_hotspot_stress_mpa"])
    assert c["max_stress_3g_mpa"] < c["yield_mpa"]
    # the floor at the thesis's M1 is above the #12 hot-spot bar (why that bar is missed)
    assert min(c["stress_floor_mpa"].values()) > 250.0
    bad = subprocess.run([sys.executable, "-m", "orchestrator.studies.arm_card", "--mesh-size",
                          "1"],
                         capture_output=True, text=True, timeout=60)
    assert bad.returncode == 2 and "--mesh-size" in bad.stderr
