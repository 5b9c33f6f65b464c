"""Picture of the arm coloured by fatigue damage (PNG), drawn by :mod:`map_render`: the plan
and side views of ALL assessed nodes (max through the thickness), the arm's outline and the
critical node."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from cosim import lower_arm as geo  # noqa: E402

from .map_render import draw  # noqa: E402


def life_text(life_km: float, life_repeats: float, fails: bool = False) -> str:
    """'min life 410.3 km (2.05e4 repeats)', or 'fails on the first cycle (life 0 km)'."""
    if fails:
        return "fails on the first cycle (life 0 km)"
    return f"min life {life_km:.4g} km ({life_repeats:.4g} repeats)"


def plot_damage_map(result, path: Path, title: str = "") -> Path:
    """Write a PNG of the damage per pass (log colour scale, see :mod:`map_render`).

    Without node coordinates (imported tables without x, y, z), or with no damage at all, a
    bar chart of the 30 most damaged nodes is drawn instead.
    """
    path = Path(path)
    D = np.asarray(result.damage, dtype=float)
    fig = plt.figure(figsize=(12, 5.2))
    if result.node_xyz is None or not np.any(D > 0):
        ax = fig.add_subplot(111)
        top = np.argsort(D)[::-1][:30]
        ax.bar([str(result.node_ids[i]) for i in top], np.where(np.isfinite(D[top]),
                                                                D[top], 0.0))
        ax.set_xlabel("node")
        ax.set_ylabel("damage per pass")
        ax.tick_params(axis="x", rotation=90)
    else:
        draw(fig, result.node_xyz, D, node_ids=result.node_ids, hardpoints=geo.HARDPOINTS)
    life = life_text(result.life_km, result.life_repeats, bool(np.isinf(D).any()))
    fig.suptitle(title or f"Lower arm fatigue damage - {life}")
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
