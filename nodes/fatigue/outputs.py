"""The batch outputs beside the damage (``suscosim fatigue``; files in the results folder,
computed as the batches pass by :mod:`.run_stream`).

* ``sn_methods`` (summary): the minimum life under both named component S-N methods,
  Shigley/Marin (with the scenario's mean-stress correction) and FKM (its own Haigh diagram,
  M_σ), each at the scenario's reliability (``component.reliability``, median by default)
  and at ``component.survival_probability``; ``life_range_km`` their range. Each is a full
  re-analysis of the same loads with that curve (the critical node may move), by the one
  config :meth:`.config.FatigueConfig.at` makes; the headline (``min_life_km``) is the entry
  of ``component.method`` at the reliability (the same config: the same numbers). FKM at a
  temperature it does not cover is left out (``left_out``, why).
* ``critical_stress.csv``: t, the six stress components and the equivalent stress at the
  critical node (Pa), by superposition of the recorded loads.
* ``rainflow_matrix.csv``: the range-mean rainflow matrix (long form, non-empty bins) of the
  critical node's equivalent stress (Pa) and of every load channel (N, N m).
* ``pseudo_damage.csv`` and ``pseudo_damage`` (summary): every load channel's pseudo-damage
  (:mod:`pseudo_damage`, k = 5).
* ``sn_plot.png`` / ``sn_plot.json``: the S-N curves (both methods, median) with the
  critical node's cycles on them (its cumulative spectrum of σar per pass at
  :data:`SN_LEVELS` levels, :class:`SnSpectrum`, and the same spectrum x the life: the
  cycles to failure).
* ``damage.vtu``: the assessed nodes with damage per pass, life (km) and log10 damage as
  point data (VTK vertices), for ParaView.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np

from .config import SN_METHODS, FatigueConfig
from .lib.counting import Cycles
from .lib.damage import sn_curve
from .lib.fkm import T_RANGE_C
from .lib.mean_stress import equivalent_amplitude
from .worker import FatigueResult


def method_table(cfg: FatigueConfig) -> tuple[list[tuple[str, float, FatigueConfig]],
                                               dict[str, str]]:
    """The entries of ``sn_methods``: (method, P, its config) for each named S-N method at
    the scenario's reliability and at ``survival_probability`` (none without a component
    curve), and the methods left out with why (FKM at a temperature it does not cover)."""
    if cfg.component is None or cfg.curve_method is None:
        return [], {}
    T = cfg.component.temperature_c
    rows: list[tuple[str, float, FatigueConfig]] = []
    left: dict[str, str] = {}
    for m in SN_METHODS:
        if m == "fkm" and not T_RANGE_C[0] <= T <= T_RANGE_C[1]:
            left[m] = (f"temperature_c = {T:g} °C: the FKM guideline covers steel from "
                       f"{T_RANGE_C[0]:g} to {T_RANGE_C[1]:g} °C")
            continue
        for P in dict.fromkeys((cfg.component.reliability, cfg.survival_probability)):
            rows.append((m, P, cfg.at(m, P)))
    return rows, left


def methods_summary(rows: list[tuple[str, float, FatigueConfig, FatigueResult]],
                    left: dict[str, str]) -> dict:
    """``sn_methods``: {"methods": {method: {repr(P): {life_km, mean_stress, ...}}},
    "life_range_km", and "left_out" when a method was}."""
    out: dict = {}
    for m, P, c, r in rows:
        sn = c.material.sn
        assert sn is not None  # a FatigueConfig's material always has its curve
        out.setdefault(m, {})[repr(float(P))] = {
            "survival_probability": P, "mean_stress": c.mean_stress_rule,
            "life_km": r.life_km, "life_repeats": r.life_repeats,
            "critical_node_id": r.critical_node_id, "max_damage_per_pass": r.max_damage,
            "Se_pa": sn.Se, "k": sn.k, "curve": sn.as_dict()}
    lives = [r.life_km for *_, r in rows]
    return {"methods": out, "life_range_km": [min(lives), max(lives)],
            **({"left_out": left} if left else {})}


SN_LEVELS = 400
"""Levels of the S-N plot's cycle spectrum: log-spaced σar from :data:`SN_LEVEL_SPAN` [0]
x the curve's Se to [1] x Su (1.7 % apart for Se = 100 MPa, Su = 600 MPa)."""
SN_LEVEL_SPAN = (0.025, 3.0)
"""The spectrum's lowest level as a fraction of Se, its highest as a multiple of Su: the plot
shows 0.05 Se to 1.5 Su."""


class SnSpectrum:
    """The critical node's cycles for the S-N plot, counted by level (nothing held per
    cycle or per sample): each cycle's corrected amplitude σar (``cfg.mean_stress_rule``, Pa) into
    :data:`SN_LEVELS` log-spaced bins; :meth:`cumulative` gives at each bin's lower edge the
    cycles whose σar is at or above it (those beyond the top edge and the infinite ones of a
    mean stress past Su counted above every level, as the sorted-cycles spectrum counted
    them). The counts are sums of 0.5 and 1: the same whatever the order the cycles come in."""

    def __init__(self, cfg: FatigueConfig) -> None:
        self.cfg = cfg
        mat = cfg.material
        curve = sn_curve(mat)
        self.M = (curve.meta or {}).get("mean_stress_sensitivity")
        lo, hi = SN_LEVEL_SPAN
        self.edges = np.geomspace(lo * curve.Se, hi * mat.Su, SN_LEVELS + 1)
        self.counts = np.zeros(SN_LEVELS)
        self.above = 0.0

    def add(self, cyc: Cycles) -> None:
        """Count closed cycles (range and mean in Pa; count 1 or 0.5)."""
        if len(cyc) == 0:
            return
        mat = self.cfg.material
        sar = equivalent_amplitude(0.5 * cyc.range, cyc.mean, self.cfg.mean_stress_rule, mat.Su,
                                   mat.sf, self.M)
        top = ~np.isfinite(sar) | (sar > self.edges[-1])
        self.above += float(np.sum(cyc.count[top]))
        h, _e = np.histogram(sar[~top], bins=self.edges, weights=cyc.count[~top])
        self.counts += h

    def cumulative(self) -> tuple[np.ndarray, np.ndarray]:
        """(σar levels [Pa], cycles at or above each) at the levels some cycle reached."""
        cum = self.above + np.cumsum(self.counts[::-1])[::-1]
        keep = self.counts > 0
        return self.edges[:-1][keep], cum[keep]


def sn_plot(path_png: Path, cfg: FatigueConfig, spectrum: SnSpectrum, result: FatigueResult,
            methods: dict | None) -> dict:
    """The S-N plot (PNG) and its data (returned, and written as JSON beside it), from the
    critical node's cycles counted by level (:class:`SnSpectrum`)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    mat = cfg.material
    curve = sn_curve(mat)
    s_lev, cum_lev = spectrum.cumulative()
    N = np.logspace(0, 9, 200)
    curves = {"primary": {"name": curve.name, "N": N.tolist(),
                          "S_pa": curve.stress(2 * N).tolist()}}
    for m, P, c in method_table(cfg)[0]:
        sn = c.material.sn
        if sn is not None and cfg.component is not None and P == cfg.component.reliability:
            curves[m] = {"name": sn.name, "N": N.tolist(), "S_pa": sn.stress(2 * N).tolist()}
    life = result.life_repeats if np.isfinite(result.life_repeats) else None
    data = {"curves": curves, "critical_node_id": result.critical_node_id,
            "mean_stress": cfg.mean_stress_rule,
            "spectrum": {"S_pa": s_lev.tolist(), "cumulative_cycles": cum_lev.tolist(),
                         "levels": f"{SN_LEVELS} log-spaced σar levels, "
                                   f"{SN_LEVEL_SPAN[0]:g} Se to {SN_LEVEL_SPAN[1]:g} Su; "
                                   "cycles at or above each level"},
            "life_repeats": life}
    fig, ax = plt.subplots(figsize=(8, 5))
    for key, cv in curves.items():
        ax.loglog(cv["N"], np.asarray(cv["S_pa"]) / 1e6, "-" if key == "primary" else "--",
                  label=f"{key}: {cv['name']}")
    if s_lev.size:
        ax.loglog(cum_lev, s_lev / 1e6, "k.", ms=3,
                  label=f"node {result.critical_node_id}: cycles per pass")
        if life:
            ax.loglog(cum_lev * life, s_lev / 1e6, ".", color="tab:red", ms=3,
                      label=f"x life ({life:.3g} passes)")
    ax.set_ylim(bottom=0.05 * curve.Se / 1e6, top=1.5 * mat.Su / 1e6)
    ax.axhline(mat.Su / 1e6, color="grey", lw=0.8, ls=":")
    ax.annotate("Su", (1.5, mat.Su / 1e6), fontsize=7, color="grey")
    ax.set_xlabel("cycles N")
    ax.set_ylabel(f"σar (MPa, {cfg.mean_stress_rule} corrected amplitude)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    ax.set_title(f"S-N curves and the cycles of the critical node {result.critical_node_id}")
    fig.tight_layout()
    fig.savefig(path_png, dpi=100)
    plt.close(fig)
    path_png.with_suffix(".json").write_text(json.dumps(data, allow_nan=False))
    return data


def write_vtu(path: Path, result: FatigueResult) -> bool:
    """``damage.vtu``: the nodes as VTK vertices with damage, life and log10 damage."""
    if result.node_xyz is None:
        return False
    import meshio  # type: ignore[import-untyped]

    D = np.asarray(result.damage, dtype=float)
    with np.errstate(divide="ignore"):
        life = np.where(D > 0, result.track_length_m / 1000.0 / D, np.inf)
        logd = np.where(D > 0, np.log10(np.where(D > 0, D, 1.0)), -300.0)
    big = np.finfo(float).max
    pts = np.asarray(result.node_xyz, dtype=float)
    mesh = meshio.Mesh(pts, [("vertex", np.arange(len(pts)).reshape(-1, 1))],
                       point_data={"damage_per_pass": np.minimum(D, big),
                                   "life_km": np.minimum(life, big),
                                   "log10_damage": np.minimum(logd, 300.0),
                                   "node_id": np.asarray(result.node_ids, dtype=np.int64)})
    mesh.write(path)
    return True


def write_pseudo_damage(path: Path, pd: list) -> None:
    """``pseudo_damage.csv``: per load channel its Basquin slope k, reference range and count,
    cycles, largest range, pseudo-damage and damage-equivalent range (:mod:`.pseudo_damage`)."""
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["channel", "k", "ref_range", "n_ref", "cycles", "max_range",
                    "pseudo_damage", "equivalent_range"])
        for p in pd:
            w.writerow([p.channel, p.k, p.ref_range, p.n_ref, p.cycles, p.max_range,
                        f"{p.pseudo_damage:.6e}", f"{p.equivalent_range:.6e}"])
