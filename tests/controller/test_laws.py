"""Switching logic and sign conventions of each law on hand-made velocity cases.

Convention: v_rel = v_w - v_b (compression positive); F_d on the body, upward positive.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from cosim.errors import InputFileError, ScenarioError
from nodes.controller.laws import COMBINATIONS, LAWS, build_controller, pnr_select
from nodes.controller.skyhook import (
    groundhook_continuous,
    groundhook_on_off,
    hybrid,
    skyhook_continuous,
    skyhook_no_jerk,
    skyhook_on_off,
)


def state(v_b, v_w, **extra):
    v_b = np.atleast_1d(np.asarray(v_b, dtype=float))
    v_w = np.atleast_1d(np.asarray(v_w, dtype=float))
    return {"z_b": np.zeros_like(v_b), "z_w": np.zeros_like(v_b), "v_b": v_b, "v_w": v_w, **extra}


# ----------------------------------------------------------------------------- TSS1


def test_tss1_hand_cases():
    #            body up, wheel still | body up, wheel faster up | body down, wheel up | v_b = 0
    v_b = np.array([0.2, 0.2, -0.1, 0.0])
    v_w = np.array([0.0, 0.5, 0.1, 0.3])
    F, c, ex = skyhook_on_off(v_b, v_w - v_b, c_soft=1500.0, c_hard=2368.0)
    hard = ex["state"] == 1.0
    # case 1: extension (v_rel = -0.2) while the body rises: hard, pulls the body down
    # case 2: compression (0.3) while the body rises: damper would push it up -> soft
    # case 3: compression (0.2) while the body falls: hard, pushes it up
    # case 4: tie (v_b = 0) -> soft
    np.testing.assert_array_equal(hard, [True, False, True, False])
    np.testing.assert_allclose(c, [2368.0, 1500.0, 2368.0, 1500.0])
    np.testing.assert_allclose(F, [-473.6, 450.0, 473.6, 450.0])


def test_tss1_controller_presets_and_output():
    ctl = build_controller({"law": "tss1"}, 1, 0.002)
    out = ctl.step(0.0, state(0.2, 0.0))
    assert out.F_d[0] == pytest.approx(-473.6)
    assert out.c_eff[0] == 2368.0 and out.extra["state"][0] == 1.0
    ctl = build_controller({"law": "tss1", "preset": "realistic"}, 1, 0.002)
    out = ctl.step(0.0, state(0.2, 0.0))
    assert out.F_d[0] == pytest.approx(-1200.0)  # 6000 * -0.2
    out = ctl.step(0.002, state(0.2, 0.5))
    assert out.F_d[0] == pytest.approx(3800.0 * 0.3) and out.extra["state"][0] == 0.0


def test_tss1_jumps_at_switching_but_no_jerk_skyhook_does_not():
    # body velocity crossing zero while the damper extends: v_rel = -0.2 fixed
    v_b = np.array([-1e-6, 1e-6])
    v_rel = np.array([-0.2, -0.2])
    F_onoff, _, _ = skyhook_on_off(v_b, v_rel, c_soft=1500.0, c_hard=2368.0)
    assert abs(F_onoff[1] - F_onoff[0]) == pytest.approx(0.2 * (2368.0 - 1500.0))
    F_nj, c_nj, _ = skyhook_no_jerk(v_b, v_rel, G=20000.0, c_min=1500.0, c_max=2368.0)
    assert abs(F_nj[1] - F_nj[0]) < 1e-3
    # no-jerk inside the region: c = G |v_b| = 20000 * 0.1 = 2000 N·s/m
    F, c, _ = skyhook_no_jerk(np.array([0.1]), np.array([-0.2]), G=20000.0, c_min=1500.0,
                              c_max=2368.0)
    assert c[0] == pytest.approx(2000.0) and F[0] == pytest.approx(-400.0)


# ------------------------------------------------------------------ continuous laws


def test_continuous_skyhook_hand_cases():
    v_b = np.array([0.2, 0.1, 0.1, 0.1])
    v_w = np.array([0.0, -0.2, -0.05, 0.3])
    F, c, _ = skyhook_continuous(v_b, v_w - v_b, c_sky=3000.0, c_min=1500.0, c_max=2368.0)
    # demands -600, -300, -300, -300 N on v_rel -0.2, -0.3, -0.15, +0.2
    np.testing.assert_allclose(c, [2368.0, 1500.0, 2000.0, 1500.0])
    np.testing.assert_allclose(F, [-473.6, -450.0, -300.0, 300.0])


def test_groundhook_hand_cases():
    v_b = np.array([0.0, 0.2])
    v_w = np.array([0.1, 0.1])
    # wheel rising and compressing (v_rel +0.1): the groundhook wants the wheel pushed down,
    # i.e. F_d = +c_gnd v_w on the body: dissipative; wheel rising but extending: not
    F, c, _ = groundhook_continuous(v_w, v_w - v_b, c_gnd=3000.0, c_min=1500.0, c_max=2368.0)
    np.testing.assert_allclose(c, [2368.0, 1500.0])
    np.testing.assert_allclose(F, [236.8, -150.0])
    F, c, ex = groundhook_on_off(v_w, v_w - v_b, c_soft=1500.0, c_hard=2368.0)
    np.testing.assert_array_equal(ex["state"], [1.0, 0.0])


def test_hybrid_limits_and_mixed_case():
    rng = np.random.default_rng(3)
    v_b, v_w = rng.normal(0, 0.3, 50), rng.normal(0, 0.3, 50)
    lim = {"c_min": 1500.0, "c_max": 2368.0}
    sky = skyhook_continuous(v_b, v_w - v_b, c_sky=4000.0, **lim)[0]
    gnd = groundhook_continuous(v_w, v_w - v_b, c_gnd=4000.0, **lim)[0]
    np.testing.assert_allclose(hybrid(v_b, v_w, alpha=1.0, G=4000.0, **lim)[0], sky)
    np.testing.assert_allclose(hybrid(v_b, v_w, alpha=0.0, G=4000.0, **lim)[0], gnd)
    # both parts active: v_b = 0.1, v_w = -0.1, v_rel = -0.2:
    # demand = 4000 (0.5 * -0.1 + 0.5 * -0.1) = -400 -> c = 2000
    F, c, _ = hybrid(np.array([0.1]), np.array([-0.1]), alpha=0.5, G=4000.0, **lim)
    assert c[0] == pytest.approx(2000.0) and F[0] == pytest.approx(-400.0)


SEMI_ACTIVE = [
    {"law": "tss1"},
    {"law": "groundhook_on_off"},
    {"law": "skyhook", "c_sky": 5000.0},
    {"law": "skyhook_no_jerk", "G": 30000.0},
    {"law": "groundhook", "c_gnd": 5000.0},
    {"law": "hybrid", "alpha": 0.4, "G": 5000.0},
]


@pytest.mark.parametrize("cfg", SEMI_ACTIVE, ids=lambda c: c["law"])
def test_semi_active_laws_never_demand_energy_input(cfg):
    rng = np.random.default_rng(11)
    ctl = build_controller(cfg, 4, 0.001)
    for k in range(200):
        s = state(rng.normal(0, 0.4, 4), rng.normal(0, 0.8, 4))
        out = ctl.step(k * 0.001, s)
        v_rel = s["v_w"] - s["v_b"]
        assert np.all(out.F_d * v_rel >= 0.0)
        # and within what the damper can do: 1500 |v| <= |F| <= 2368 |v|
        assert np.all(np.abs(out.F_d) <= 2368.0 * np.abs(v_rel) + 1e-9)
        assert np.all(np.abs(out.F_d) >= 1500.0 * np.abs(v_rel) - 1e-9)


def test_passive_laws():
    out = build_controller({"law": "passive", "c": 1200}, 1, 0.001).step(0.0, state(0.1, -0.1))
    assert out.F_d[0] == pytest.approx(-240.0) and out.c_eff[0] == 1200.0
    ctl = build_controller({"law": "passive_curve", "points": [[-0.2, -1000], [0.2, 400]]}, 2, 1e-3)
    out = ctl.step(0.0, state([0.0, 0.0], [0.1, -0.1]))
    np.testing.assert_allclose(out.F_d, [200.0, -500.0])
    np.testing.assert_allclose(out.c_eff, [2000.0, 5000.0])


# -------------------------------------------------------------------------- PnR


def brute_force_pnr(v_rel, c_soft, c_hard, theta, phi):
    """Independent restatement of Eqs 5.6-5.12: loop over the 16 combinations."""
    best = None
    for n, pattern in enumerate(itertools.product("SH", repeat=4)):  # FL is the MSB
        d = [(c_hard if p == "H" else c_soft) * v for p, v in zip(pattern, v_rel, strict=True)]
        if abs(theta) > abs(phi):
            P = (d[0] + d[1] - d[2] - d[3]) * theta
        else:
            P = (d[0] + d[2] - d[1] - d[3]) * phi
        if best is None or P < best[0]:
            best = (P, n, "".join(pattern))
    return best[1], best[2]


def combination_label(index: int) -> str:
    """Table 5.2 name of combination ``index`` (0-based), e.g. 8 -> ``"MP9 HSSS"``."""
    return f"MP{index + 1} " + "".join("H" if h else "S" for h in COMBINATIONS[index])


def test_table_5_2_combinations():
    assert combination_label(0) == "MP1 SSSS"
    assert combination_label(4) == "MP5 SHSS"  # the OCR's "SHSH" is a duplicate of MP6
    assert combination_label(8) == "MP9 HSSS"
    assert combination_label(15) == "MP16 HHHH"
    assert len({tuple(r) for r in COMBINATIONS}) == 16


@pytest.mark.parametrize(
    ("v_rel", "theta", "phi", "label"),
    [
        # left compressing, right extending; nose-up pitch acc dominates:
        # min of 0.1(c_FL - c_FR - c_RL + c_RR) -> FL soft, FR hard, RL hard, RR soft
        ([0.1, -0.1, 0.1, -0.1], 1.0, 0.2, "MP7 SHHS"),
        # roll dominates (left up): min of 0.1 c_FL + 0.1 c_RL + 0.1 c_FR + 0.1 c_RR -> soft
        ([0.1, -0.1, 0.1, -0.1], 0.2, 1.0, "MP1 SSSS"),
        ([0.1, -0.1, 0.1, -0.1], 0.2, -1.0, "MP16 HHHH"),
        # roll: min of 0.1 c_FL - 0.1 c_RL - 0.1 c_FR - 0.2 c_RR -> S H H H
        ([0.1, 0.1, -0.1, 0.2], 0.0, 1.0, "MP8 SHHH"),
        # no angular acceleration: every product is 0, the first (all soft) is kept
        ([0.3, -0.2, 0.1, 0.05], 0.0, 0.0, "MP1 SSSS"),
    ],
)
def test_pnr_minimum_product_hand_cases(v_rel, theta, phi, label):
    n, F, c = pnr_select(np.array(v_rel), 1500.0, 2368.0, theta, phi)
    assert combination_label(n) == label
    np.testing.assert_allclose(F, c * np.array(v_rel))


def test_pnr_matches_brute_force_and_opposes_the_motion():
    rng = np.random.default_rng(5)
    for _ in range(300):
        v = rng.normal(0, 0.3, 4)
        theta, phi = rng.normal(0, 2.0, 2)
        n, F, _ = pnr_select(v, 1500.0, 2368.0, theta, phi)
        n_ref, _ = brute_force_pnr(v, 1500.0, 2368.0, theta, phi)
        assert n == n_ref
        # the chosen nose-up (or left-up) damper moment is the one least aligned with the
        # angular acceleration: no other combination opposes it more
        if abs(theta) > abs(phi):
            moment, acc = F[0] + F[1] - F[2] - F[3], theta
        else:
            moment, acc = F[0] + F[2] - F[1] - F[3], phi
        all_F = np.where(COMBINATIONS, 2368.0, 1500.0) * v
        all_m = (
            all_F[:, 0] + all_F[:, 1] - all_F[:, 2] - all_F[:, 3]
            if abs(theta) > abs(phi)
            else all_F[:, 0] + all_F[:, 2] - all_F[:, 1] - all_F[:, 3]
        )
        assert moment * acc <= np.min(all_m * acc) + 1e-9


def body(w_pitch=0.0, w_roll=0.0):
    return {"v_heave": 0.0, "w_pitch": w_pitch, "w_roll": w_roll, "pitch": 0.0, "roll": 0.0}


def test_pnr_controller_iso_signs_from_rates():
    ctl = build_controller({"law": "pnr"}, 4, 0.001)
    v_b = np.zeros(4)
    v_w = np.array([0.1, -0.1, 0.1, -0.1])
    first = ctl.step(0.0, state(v_b, v_w, **body()))
    assert first.extra["mp"][0] == 1.0  # no acceleration known yet: all soft
    # ISO pitch rate about +y going negative = nose going up, accelerating: theta'' = +1 rad/s²
    out = ctl.step(0.001, state(v_b, v_w, **body(w_pitch=-0.001)))
    assert out.extra["theta_dd"][0] == pytest.approx(1.0)
    assert out.extra["mp"][0] == 7.0  # SHHS, as in the hand case above
    np.testing.assert_allclose(out.F_d, [150.0, -236.8, 236.8, -150.0])


def test_pnr_controller_from_corner_accelerations():
    ctl = build_controller(
        {"law": "pnr", "angular_acc": "corners", "wheelbase": 2.5, "track": 1.5}, 4, 0.001
    )
    # front-left accelerating up relative to rear-left: nose-up 2/2.5 = 0.8; roll (1-1)/1.5 = 0
    a_b = np.array([1.0, 1.0, -1.0, -1.0])
    out = ctl.step(0.0, state(np.zeros(4), [0.1, -0.1, 0.1, -0.1], a_b=a_b, **body()))
    assert out.extra["theta_dd"][0] == pytest.approx(0.8)
    assert out.extra["mp"][0] == 7.0


# ------------------------------------------------------------------------ MR laws


def sine_run(cfg, f_hz, h=5e-4, periods=3):
    """Prescribed wheel/body motion (10 mm wheel sine, body lagging at 30 %)."""
    ctl = build_controller(cfg, 1, h)
    w = 2 * np.pi * f_hz
    rows = []
    for t in np.arange(0.0, periods / f_hz, h):
        v_w = 0.01 * w * np.cos(w * t)
        v_b = 0.003 * w * np.cos(w * t - 1.0)
        out = ctl.step(t, state(v_b, v_w))
        rows.append((v_b, v_w - v_b, out.F_d[0], out.extra.get("I", [np.nan])[0]))
    return np.array(rows)


def test_tss3_current_is_exactly_zero_or_max_by_the_skyhook_condition():
    r = sine_run({"law": "tss3"}, 1.5)
    v_b, v_rel, _, current = r.T
    expected = np.where(v_b * v_rel < 0.0, 0.6, 0.0)
    np.testing.assert_array_equal(current, expected)


def test_tss2_tracks_tss1_better_than_tss3():
    ref = sine_run({"law": "tss1", "preset": "realistic"}, 1.5)
    tss2 = sine_run({"law": "tss2", "preset": "realistic"}, 1.5)
    tss3 = sine_run({"law": "tss3"}, 1.5)
    n = len(ref) // 3  # skip the first period
    rms = lambda x: float(np.sqrt(np.mean(x[n:] ** 2)))  # noqa: E731
    err2 = rms(tss2[:, 2] - ref[:, 2])
    err3 = rms(tss3[:, 2] - ref[:, 2])
    assert err2 < 0.2 * rms(ref[:, 2])
    assert err2 < 0.25 * err3
    assert np.all((tss2[:, 3] >= 0.0) & (tss2[:, 3] <= 0.6))
    assert 0.0 < np.mean(tss2[n:, 3]) < np.mean(tss3[n:, 3])


def test_tss2_static_loop_solution():
    # dynamics off: I solves I = G(|F*| - B |F_MR(I)|) exactly
    ctl = build_controller(
        {"law": "tss2", "preset": "realistic", "damper": {"dynamics": False}}, 1, 1e-3
    )
    out = ctl.step(0.0, state(0.2, 0.0))  # hard: F* = 6000 * -0.2 = -1200 N
    I = out.extra["I"][0]
    assert out.extra["F_demand"][0] == pytest.approx(-1200.0)
    assert 0.0 < I < 0.6
    assert I == pytest.approx(0.001 * (1200.0 - 0.8 * abs(out.F_d[0])), abs=1e-9)
    assert out.F_d[0] < 0.0


def test_passive_mr_zero_current_is_close_to_3800_linear():
    r = sine_run({"law": "passive_mr", "damper": {"dynamics": False}}, 5.0)
    _, v_rel, F, current = r.T
    assert np.all(current == 0.0)
    big = np.abs(v_rel) > 0.1
    ratio = F[big] / v_rel[big]
    assert np.all((ratio > 3203.0) & (ratio < 3230.0))  # c_post(0) + 1.33 N / |v|


# ------------------------------------------------------------------------ errors


@pytest.mark.parametrize(
    ("cfg", "key"),
    [
        ({"law": "skyhok"}, "controller.law"),
        ({}, "controller.law"),
        ({"law": "tss1", "c_sky": 4000}, "controller.c_sky"),
        ({"law": "passive", "c": -5}, "controller.c"),
        ({"law": "passive", "c": "soft"}, "controller.c"),
        ({"law": "tss1", "c_soft": 3000, "c_hard": 2000}, "controller.c_hard"),
        ({"law": "tss1", "preset": "heavy"}, "controller.preset"),
        ({"law": "skyhook"}, "controller.c_sky"),
        ({"law": "hybrid", "alpha": 1.5, "G": 10}, "controller.alpha"),
        ({"law": "tss2", "damper": {"K_f": 0}}, "controller.damper.K_f"),
        ({"law": "tss3", "I_hard": 0.9}, "controller.I_hard"),
        ({"law": "pnr", "angular_acc": "corners"}, "controller.wheelbase"),
        ({"law": "passive_curve", "points": [[0, 1, 2]]}, "controller.points"),
        ({"law": "passive_curve"}, "controller.curve"),
    ],
)
def test_bad_config_names_the_key(cfg, key):
    with pytest.raises(ScenarioError) as err:
        build_controller(cfg, 4, 0.001)
    assert err.value.key == key


def test_pnr_needs_four_corners():
    with pytest.raises(ScenarioError, match="4 corners"):
        build_controller({"law": "pnr"}, 1, 0.001)


def test_bad_curve_file_raises_input_file_error(tmp_path):
    p = tmp_path / "c.csv"
    p.write_text("-0.1,100\n0.1,100\n")
    with pytest.raises(InputFileError) as err:
        build_controller({"law": "passive_curve", "curve": str(p)}, 1, 0.001)
    assert err.value.line == 1


def test_every_registered_law_builds_with_its_documented_minimum():
    minimum = {
        "passive_curve": {"points": [[-1, -1], [1, 1]]},
        "skyhook": {"c_sky": 1.0},
        "skyhook_no_jerk": {"G": 1.0},
        "groundhook": {"c_gnd": 1.0},
        "hybrid": {"alpha": 0.5, "G": 1.0},
    }
    for law in LAWS:
        if law == "fmu":  # needs an FMU file: tests/controller/test_fmu.py
            continue
        ctl = build_controller({"law": law, **minimum.get(law, {})}, 4, 0.001)
        out = ctl.step(0.0, state(np.full(4, 0.1), np.zeros(4), **body()))
        assert out.F_d.shape == (4,) and out.c_eff.shape == (4,)
        assert np.all(out.F_d * (0.0 - 0.1) >= 0.0)


def test_state_with_wrong_corner_count_is_rejected():
    ctl = build_controller({"law": "tss1"}, 4, 0.001)
    with pytest.raises(ValueError, match="expected 4"):
        ctl.step(0.0, state([0.1, 0.2], [0.0, 0.0]))


def test_mr_laws_run_their_loop_at_the_substep_not_the_communication_step():
    # on a prescribed motion the MR force at t does not depend on the communication step,
    # because the damper and the current rule are integrated in substeps between calls
    for cfg in ({"law": "tss2", "preset": "realistic"}, {"law": "tss3"}):
        fine = sine_run(cfg, 5.0, h=5e-4)
        coarse = sine_run(cfg, 5.0, h=2e-3)
        t_fine = np.arange(len(fine)) * 5e-4
        t_coarse = np.arange(len(coarse)) * 2e-3
        n = len(coarse) // 3
        ref = np.interp(t_coarse, t_fine, fine[:, 2])
        err = np.sqrt(np.mean((coarse[n:, 2] - ref[n:]) ** 2))
        assert err < 0.02 * np.sqrt(np.mean(ref[n:] ** 2))
