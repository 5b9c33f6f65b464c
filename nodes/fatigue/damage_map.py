"""Picture of the arm coloured by fatigue damage (PNG): top and bottom surfaces."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import LogNorm  # noqa: E402

from cosim import lower_arm as geo  # noqa: E402


def plot_damage_map(result, path: Path, title: str = "") -> Path:
    """Write a PNG: damage per pass (log colour scale) on the arm's top and bottom faces.

    Without node coordinates (imported tables without x, y, z), a bar chart of the 30 most
    damaged nodes is drawn instead.
    """
    path = Path(path)
    D = np.asarray(result.damage)
    pos = D[D > 0]
    fig = plt.figure(figsize=(11, 5.2))
    if result.node_xyz is None or pos.size == 0:
        ax = fig.add_subplot(111)
        top = np.argsort(D)[::-1][:30]
        ax.bar([str(result.node_ids[i]) for i in top], D[top])
        ax.set_xlabel("node")
        ax.set_ylabel("damage per pass")
        ax.tick_params(axis="x", rotation=90)
    else:
        xyz = result.node_xyz
        norm = LogNorm(vmin=max(pos.min(), pos.max() * 1e-8), vmax=pos.max())
        zmax, zmin = xyz[:, 2].max(), xyz[:, 2].min()
        crit = result.critical_node
        for k, (label, zf) in enumerate((("top (z > 0)", zmax), ("bottom (z < 0)", zmin))):
            ax = fig.add_subplot(1, 2, k + 1)
            on = np.isclose(xyz[:, 2], zf)
            d = np.where(D[on] > 0, D[on], norm.vmin)
            sc = ax.scatter(xyz[on, 0] * 1e3, xyz[on, 1] * 1e3, c=d, norm=norm, s=14,
                            cmap="inferno_r", edgecolors="none")
            for name, p in geo.HARDPOINTS.items():
                ax.plot(p[0] * 1e3, p[1] * 1e3, "k+", ms=9)
                ax.annotate(name, (p[0] * 1e3, p[1] * 1e3), fontsize=7,
                            xytext=(4, 4), textcoords="offset points")
            if np.isclose(xyz[crit, 2], zf):
                ax.plot(xyz[crit, 0] * 1e3, xyz[crit, 1] * 1e3, "o", mfc="none", mec="c",
                        ms=14, mew=2, label=f"critical node {result.critical_node_id}")
                ax.legend(loc="lower right", fontsize=8)
            ax.set_aspect("equal")
            ax.set_xlabel("x (mm, forward)")
            ax.set_ylabel("y (mm, outboard)")
            ax.set_title(label)
        fig.colorbar(sc, ax=fig.axes, label="Miner damage per pass", shrink=0.8)
    life = result.life_km
    fig.suptitle(title or f"Lower arm fatigue damage - min life {life:.4g} km "
                          f"({result.life_repeats:.4g} repeats)")
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
