"""#30 item 1: the damage map projects ALL nodes (any mesh), so the critical node shows
wherever it is through the thickness; the rendered data has its marker and its damage."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from nodes.fatigue.map_render import draw, project  # noqa: E402


def cloud(seed: int = 3, n: int = 3000) -> np.ndarray:
    """An irregular (tetrahedral-like) node cloud: a 0.3 m plate with a hole, 30 mm thick."""
    rng = np.random.default_rng(seed)
    p = rng.uniform([-0.15, 0.0, -0.015], [0.15, 0.3, 0.015], (4 * n, 3))
    keep = np.hypot(p[:, 0], p[:, 1] - 0.15) > 0.05
    return p[keep][:n]


def test_critical_node_inside_the_thickness_is_marked_with_its_damage() -> None:
    xyz = cloud()
    rng = np.random.default_rng(1)
    D = 10.0 ** rng.uniform(-12, -7, len(xyz))
    # the critical node at mid-thickness (z ~ 0): the old map, kept only z = +-z_max, lost it
    c = int(np.argmin(np.abs(xyz[:, 2]) + np.abs(xyz[:, 0] - 0.1)))
    D[c] = 1e-4
    ids = np.arange(len(xyz)) + 1000
    fig = plt.figure(figsize=(10, 4))
    out = draw(fig, xyz, D, node_ids=ids)
    assert out["critical"] == c and out["critical_id"] == 1000 + c
    for view, P in out["projections"].items():
        assert P.value_at(c) == 1e-4, view  # its bin shows the largest damage
        # every node is represented: its bin holds at least its own damage
        vals = P.grid[P.node_bin[:, 0], P.node_bin[:, 1]]
        assert np.all(vals >= D)
    marks = [ln for ax in fig.axes for ln in ax.get_lines()
             if ln.get_label() == f"critical node {1000 + c}"]
    assert len(marks) == 2
    plan, side = marks
    assert plan.get_xdata()[0] == pytest.approx(xyz[c, 0] * 1e3)
    assert plan.get_ydata()[0] == pytest.approx(xyz[c, 1] * 1e3)
    assert side.get_ydata()[0] == pytest.approx(xyz[c, 2] * 1e3)
    plt.close(fig)


def test_hole_stays_empty_and_max_wins_in_a_bin() -> None:
    xyz = cloud()
    P = project(xyz, np.ones(len(xyz)), "plan", h=0.01)
    # the bin at the hole's centre (0, 0.15) is empty
    i = int((0.0 - P.x_edges[0]) / 0.01)
    j = int((0.15 - P.y_edges[0]) / 0.01)
    assert np.isnan(P.grid[i, j])
    two = np.array([[0.0, 0.0, -0.01], [0.0, 0.0, 0.01], [0.05, 0.0, 0.0]])
    Q = project(two, np.array([1.0, 5.0, 2.0]), "plan", h=0.01)
    assert Q.value_at(0) == Q.value_at(1) == 5.0 and Q.value_at(2) == 2.0


def test_infinite_damage_is_drawn_not_an_error() -> None:
    """A node that fails on the first cycle (D = inf) is a result (#30 item 2)."""
    xyz = cloud(n=500)
    D = np.full(len(xyz), 1e-9)
    D[7] = np.inf
    fig = plt.figure()
    out = draw(fig, xyz, D)
    assert out["critical"] == 7 and out["fails_first_cycle"] == 1
    assert out["projections"]["plan"].value_at(7) == np.inf
    fig.canvas.draw()
    plt.close(fig)
