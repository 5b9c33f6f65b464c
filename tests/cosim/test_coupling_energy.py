"""The coupling's energy residual (cosim/coupling_energy.py, issue #29)."""

from __future__ import annotations

import numpy as np
import pytest

from cosim import coupling_energy as ce


def _damper_table(v_rel: np.ndarray, c: float, lag: int) -> dict[str, np.ndarray]:
    """A linear damper F = c v_rel computed from the plant's state of step k - lag."""
    n = len(v_rel)
    seen = np.concatenate([np.repeat(v_rel[:1], lag), v_rel[: n - lag]])
    return {"plant/state/v_w": v_rel.copy(), "plant/state/v_b": np.zeros(n),
            "controller/force/F_d": c * seen, "controller/force/c_eff": np.full(n, c)}


V = np.sin(np.linspace(0.0, 6.0, 400)) + 0.3 * np.cos(np.linspace(0.0, 17.0, 400))


@pytest.mark.parametrize("exchange,lag", [("sequential", 0), ("parallel", 1)])
def test_a_linear_damper_linearised_exactly_has_no_residual(exchange: str, lag: int) -> None:
    r = ce.coupling_residual(_damper_table(V, 1500.0, lag), 1e-3, "jacobian", exchange)
    assert set(r) == {"damper"}
    assert r["damper"].carried > 0
    assert r["damper"].abs_residual == pytest.approx(0.0, abs=1e-12)


def test_held_damper_force_residual_is_the_hand_calculation() -> None:
    h, c = 2e-3, 1500.0
    r = ce.coupling_residual(_damper_table(V, c, 0), h, "hold", "sequential")["damper"]
    # held F_k against F(x_k+1) = c v_k+1 at the step's end; nothing at its start
    hand = 0.5 * h * (c * V[:-1] - c * V[1:]) * V[1:]
    np.testing.assert_allclose(r.dE, hand, rtol=0, atol=1e-12)
    assert r.abs_residual == pytest.approx(np.abs(hand).sum())
    assert r.carried == pytest.approx(h * np.abs(c * V * V).sum())
    assert 0 < r.relative < 1


def test_parallel_hold_counts_the_delay_at_both_ends_of_the_step() -> None:
    h, c = 1e-3, 1000.0
    r = ce.coupling_residual(_damper_table(V, c, 1), h, "hold", "parallel")["damper"]
    k = np.arange(1, len(V) - 2)
    F = c * np.concatenate([V[:1], V[:-1]])
    hand = 0.5 * h * ((F[k] - F[k + 1]) * V[k] + (F[k] - F[k + 2]) * V[k + 1])
    np.testing.assert_allclose(r.dE, hand, atol=1e-12)
    seq = ce.coupling_residual(_damper_table(V, c, 0), h, "hold", "sequential")["damper"]
    assert r.relative > seq.relative  # one more step of delay, more residual


def test_tyre_bond_jacobian_sees_only_the_road_moving_within_the_step() -> None:
    n, h, k_t = 300, 1e-3, 2e5
    t = np.arange(n) * h
    z_w = 0.01 * np.sin(8 * t)
    v_w = 0.08 * np.cos(8 * t)
    z_g = 0.004 * np.sin(30 * t)
    table = {"plant/state/v_w": v_w, "plant/state/v_b": np.zeros(n),
             "plant/state/z_w": z_w, "tyre_road/force/F_t": 4000 + k_t * (z_g - z_w),
             "tyre_road/force/k_t": np.full(n, k_t)}
    r = ce.coupling_residual(table, h, "jacobian", "sequential")["tyre"]
    hand = 0.5 * h * (-k_t * (z_g[1:] - z_g[:-1])) * v_w[1:]
    np.testing.assert_allclose(r.dE, hand, atol=1e-9)
    flat = dict(table, **{"tyre_road/force/F_t": 4000 + k_t * (0.0 - z_w)})
    assert ce.coupling_residual(flat, h, "jacobian", "sequential")["tyre"].abs_residual \
        == pytest.approx(0.0, abs=1e-9)


def test_per_corner_columns_are_summed_and_summary_totals() -> None:
    one = _damper_table(V, 1500.0, 0)
    four = {f"{name}[{i}]": col * (i + 1) for name, col in one.items() for i in range(4)}
    r1 = ce.coupling_residual(one, 1e-3, "hold", "sequential")
    r4 = ce.coupling_residual(four, 1e-3, "hold", "sequential")
    # corner i scales F and v by (i+1): residual and carried energy by (i+1)^2
    scale = sum((i + 1) ** 2 for i in range(4))
    assert r4["damper"].abs_residual == pytest.approx(scale * r1["damper"].abs_residual)
    assert r4["damper"].relative == pytest.approx(r1["damper"].relative)
    s = ce.summary(r4)
    assert s["total"] == pytest.approx(s["damper"])


def test_unknown_coupling_is_refused() -> None:
    with pytest.raises(ValueError, match="coupling"):
        ce.coupling_residual(_damper_table(V, 1.0, 0), 1e-3, "spline", "sequential")
