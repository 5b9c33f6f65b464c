"""The one damage-map renderer: a projection of ALL assessed nodes, for any mesh.

Used by the run's ``fatigue/damage_map.png`` (:func:`plot_damage_map`), the run report, the sweep
report (which embeds each run's PNG) and the duty report. It needs node positions only
(``xyz`` in m, the arm frame: x forward, y outboard, z up), so it works for the mapped hex
mesh, a tetrahedral mesh or an imported node table alike.

**Projection.** Two views: the plan (x-y) and the side (x-z). Each view is cut into square
bins of side ``h`` (default: the median distance of the nodes in that view to their 4th
nearest neighbour: robust to a mapped mesh's long thin cells); a bin's value is the
**largest** damage of the nodes that project into it (the worst through the thickness,
whatever z). The silhouette is the occupied bins closed by one bin (a morphological closing,
so the gaps between mesh lines do not show as holes while the lightening hole does); an empty
bin inside it is drawn with the largest value of its 3 x 3 neighbours, and the silhouette's
edge is drawn as the outline. The critical node is marked where it projects, with its id.

Damage is per pass (or per schedule, for a duty). A node whose damage is infinite (it fails
on the first cycle) is drawn in the colour map's "over" colour (blue) and said in the title.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

VIEWS = {"plan": (0, 1), "side": (0, 2)}
"""View name -> the two axes (indices into xyz) it shows."""
AXIS_LABELS = ("x (mm, forward)", "y (mm, outboard)", "z (mm, up)")


@dataclass(frozen=True)
class Projection:
    """One view's binned maximum: ``grid[i, j]`` = max damage in bin (x_edges[i], y_edges[j])
    (NaN where no node falls), ``node_bin`` the (i, j) of every node. Lengths in m."""

    axes: tuple[int, int]
    x_edges: np.ndarray
    y_edges: np.ndarray
    grid: np.ndarray
    node_bin: np.ndarray  # (n_nodes, 2) int

    @property
    def occupied(self) -> np.ndarray:
        return ~np.isnan(self.grid)

    def value_at(self, node: int) -> float:
        """The bin value where node ``node`` (an index) projects."""
        i, j = self.node_bin[node]
        return float(self.grid[i, j])


def bin_size(p: np.ndarray, k: int = 4) -> float:
    """The median distance of 2-D points ``p`` to their k-th nearest neighbour (m); > 0."""
    from scipy.spatial import cKDTree

    u = np.unique(np.round(p, 9), axis=0)
    if len(u) < 2:
        return 1e-3
    kk = min(k, len(u) - 1)
    d, _ = cKDTree(u).query(u, k=kk + 1)
    return float(max(np.median(d[:, kk]), 1e-6))


def silhouette(P: Projection) -> tuple[np.ndarray, np.ndarray]:
    """(closed occupancy mask, grid with the empty bins inside it filled by their 3 x 3
    neighbours' maximum) of a projection (module docstring)."""
    from scipy import ndimage

    occ = P.occupied
    padded = np.pad(occ, 1)
    closed = ndimage.binary_closing(padded, structure=np.ones((3, 3), bool))[1:-1, 1:-1]
    closed |= occ
    g = np.where(occ, P.grid, -np.inf)
    nb = ndimage.maximum_filter(g, size=3, mode="constant", cval=-np.inf)
    filled = np.where(occ, P.grid, np.where(closed & np.isfinite(nb) | (nb == np.inf), nb,
                                            np.nan))
    return closed, filled


def project(xyz: np.ndarray, values: np.ndarray, view: str = "plan",
            h: float | None = None) -> Projection:
    """The max of ``values`` per bin of ``view`` (see module docstring). Non-finite values
    are kept (inf wins the max; NaN is ignored)."""
    xyz = np.asarray(xyz, dtype=float)
    v = np.asarray(values, dtype=float)
    if xyz.ndim != 2 or xyz.shape[1] != 3 or len(xyz) != len(v) or len(v) == 0:
        raise ValueError(f"need xyz (n, 3) and n values, got {xyz.shape} and {v.shape}")
    a, b = VIEWS[view]
    p = xyz[:, [a, b]]
    h = bin_size(p) if h is None else float(h)
    lo = p.min(axis=0) - 0.5 * h
    n = np.maximum(np.ceil((p.max(axis=0) + 0.5 * h - lo) / h).astype(int), 1)
    idx = np.minimum(((p - lo) / h).astype(int), n - 1)
    grid = np.full((int(n[0]), int(n[1])), -np.inf)
    np.maximum.at(grid, (idx[:, 0], idx[:, 1]), np.where(np.isnan(v), -np.inf, v))
    seen = np.zeros(grid.shape, bool)
    seen[idx[:, 0], idx[:, 1]] = True
    grid = np.where(seen, np.maximum(grid, 0.0), np.nan)
    return Projection((a, b), lo[0] + h * np.arange(n[0] + 1), lo[1] + h * np.arange(n[1] + 1),
                      grid, idx)


def draw(fig: Any, xyz: np.ndarray, damage: np.ndarray, *,
         node_ids: Sequence[int] | np.ndarray | None = None,
         hardpoints: Mapping[str, Any] | None = None,
         label: str = "Miner damage per pass", views: Sequence[str] = ("plan", "side"),
         h: float | None = None) -> dict:
    """Draw the views of ``damage`` on ``fig`` (one axes per view, side by side); return
    what was drawn: ``{"critical": index, "critical_id": id, "projections": {view: P},
    "fails_first_cycle": n}`` (the data a test or a caller checks)."""
    import matplotlib as mpl
    from matplotlib.colors import LogNorm

    D = np.asarray(damage, dtype=float)
    xyz = np.asarray(xyz, dtype=float)
    crit = int(np.nanargmax(np.where(np.isnan(D), -np.inf, D)))
    cid = int(node_ids[crit]) if node_ids is not None else crit
    finite_pos = D[np.isfinite(D) & (D > 0)]
    n_inf = int(np.isinf(D).sum())
    vmax = float(finite_pos.max()) if finite_pos.size else 1.0
    vmin = max(float(finite_pos.min()), vmax * 1e-8) if finite_pos.size else vmax * 1e-8
    if vmin >= vmax:
        vmin = vmax / 10.0
    norm = LogNorm(vmin=vmin, vmax=vmax)
    base = mpl.colormaps["inferno_r"]
    cmap = base.with_extremes(over="tab:blue", under=base(0.0), bad="white")
    out: dict = {"critical": crit, "critical_id": cid, "projections": {},
                 "fails_first_cycle": n_inf}
    mesh = None
    for k, view in enumerate(views):
        ax = fig.add_subplot(1, len(views), k + 1)
        P = project(xyz, D, view, h)
        out["projections"][view] = P
        a, b = P.axes
        closed, filled = silhouette(P)
        shown = np.where(closed & (filled <= 0), vmin * 0.5, filled)  # zero -> "under"
        mesh = ax.pcolormesh(P.x_edges * 1e3, P.y_edges * 1e3, np.ma.masked_invalid(shown).T,
                             norm=norm, cmap=cmap, shading="flat")
        xc = 0.5 * (P.x_edges[:-1] + P.x_edges[1:]) * 1e3
        yc = 0.5 * (P.y_edges[:-1] + P.y_edges[1:]) * 1e3
        if P.grid.shape[0] > 1 and P.grid.shape[1] > 1:
            ax.contour(xc, yc, closed.T.astype(float), levels=[0.5], colors="k",
                       linewidths=0.8)
        for name, hp in (hardpoints or {}).items():
            ax.plot(hp[a] * 1e3, hp[b] * 1e3, "k+", ms=8)
            ax.annotate(name, (hp[a] * 1e3, hp[b] * 1e3), fontsize=6, xytext=(3, 3),
                        textcoords="offset points")
        ax.plot([xyz[crit, a] * 1e3], [xyz[crit, b] * 1e3], "o", mfc="none", mec="c", ms=14,
                mew=2, label=f"critical node {cid}")
        ax.annotate(f"critical node {cid}", (xyz[crit, a] * 1e3, xyz[crit, b] * 1e3),
                    xytext=(10, -12), textcoords="offset points", fontsize=7, color="teal")
        ax.set_aspect("equal")
        ax.set_xlabel(AXIS_LABELS[a])
        ax.set_ylabel(AXIS_LABELS[b])
        ax.set_title(f"{view} view: max over {'z' if view == 'plan' else 'y'}", fontsize=9)
    if mesh is not None:
        fig.colorbar(mesh, ax=fig.axes, label=label, shrink=0.8,
                     extend="max" if n_inf else "neither")
    return out


def plot_damage_map(result: Any, path: Path, title: str = "") -> Path:
    """Write a PNG of a :class:`.lib.result.FatigueResult`'s damage per pass (:func:`draw`:
    plan and side views, the arm's outline and the critical node); without node coordinates
    (imported tables without x, y, z), or with no damage at all, a bar chart of the 30 most
    damaged nodes."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from cosim import lower_arm as geo

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
    life = "fails on the first cycle (life 0 km)" if np.isinf(D).any() else \
        f"min life {result.life_km:.4g} km ({result.life_repeats:.4g} repeats)"
    fig.suptitle(title or f"Lower arm fatigue damage - {life}")
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
