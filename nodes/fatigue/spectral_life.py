"""The frequency-domain life of a run or a load file (``method = "dirlik"`` or
``"tovo_benasciutti"``): per node, the signed equivalent stress of the whole history
(superposition, as the rainflow method's), its Welch PSD, the method's cycle-amplitude density
and Miner's sum with the stress-life S-N curve, mean-stress rule and endurance rule of the
config (:mod:`.spectral`), as a `FatigueResult` like the rainflow method's.

What differs from the rainflow result: ``n_cycles`` is the expected count nu_p T (cycles at the
peak rate), ``eq_range_max`` the history's max - min (rainflow's largest range, which spans the
extremes); every node is computed (no screening). Nodes are done `NODE_CHUNK` at a time so
that memory does not grow with the mesh (6 x samples x chunk stresses).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from cosim.errors import ScenarioError

from .config import FatigueConfig
from .lib import spectral
from .lib.damage import cycle_reversals
from .lib.equivalent_stress import equivalent_of
from .lib.result import FatigueResult
from .lib.superposition import node_major, superpose_components
from .worker import _case_columns, _matrix, load_influence

NODE_CHUNK = 256


def spectral_analyse(t: np.ndarray, loads: Mapping[str, np.ndarray], cfg: FatigueConfig,
                     track_length_m: float) -> tuple[FatigueResult, dict]:
    """(result, its ``spectral`` summary entry) of one pass of ``loads`` [N] at times ``t``
    [s] (uniform steps: the PSD needs them) over ``track_length_m`` [m]."""
    if cfg.critical_plane is not None:
        raise ScenarioError("fatigue.equivalent", cfg.critical_plane, f"abs_max_principal or "
                            f"signed_von_mises with method {cfg.method!r} (the critical planes "
                            "count the shear's cycles: method = \"stress_life\")")
    t = np.asarray(t, dtype=float)
    dt = np.diff(t)
    if t.size < 8 or np.ptp(dt) > 1e-6 * float(np.median(dt)):
        raise ScenarioError("fatigue.method", cfg.method, "a load history at a constant time "
                            "step (>= 8 samples) for its PSD, or method = \"stress_life\"")
    fs = 1.0 / float(np.median(dt))
    inf = load_influence(cfg)
    names = list(loads)
    cols, missing = _case_columns(inf.case_names, names)
    F = _matrix(cols, [np.asarray(loads[k], dtype=float) for k in names], t.size)
    per_node = node_major(inf.coefficients)
    n = inf.n_nodes
    duration = t.size / fs
    out = {k: np.empty(n) for k in ("damage", "eq_max", "eq_min", "n_cycles")}
    m_all = np.empty((4, n))

    def reversals(s1: np.ndarray, s2: np.ndarray) -> np.ndarray:
        return cycle_reversals(s1, s2, cfg.material, "stress_life", cfg.mean_stress_rule,
                               cfg.endurance)
    for j in range(0, n, NODE_CHUNK):
        sl = slice(j, min(n, j + NODE_CHUNK))
        x = np.ascontiguousarray(equivalent_of(superpose_components(F, per_node[sl]),
                                               cfg.equivalent).T)  # (k, samples)
        f, G = spectral.welch_psd(x, fs)
        m = spectral.moments(f, G)
        m_all[:, sl] = m
        out["damage"][sl] = spectral.damage_rate(cfg.method, m, x.mean(axis=1),
                                                 reversals) * duration
        out["eq_max"][sl], out["eq_min"][sl] = x.max(axis=1), x.min(axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            out["n_cycles"][sl] = np.nan_to_num(np.sqrt(m[3] / m[2])) * duration
    result = FatigueResult(
        damage=out["damage"], node_ids=inf.node_ids, node_xyz=inf.node_xyz,
        eq_max=out["eq_max"], eq_min=out["eq_min"], eq_range_max=out["eq_max"] - out["eq_min"],
        n_cycles=out["n_cycles"], track_length_m=float(track_length_m), duration_s=duration,
        n_samples=int(t.size), config=cfg.as_dict(), influence_meta=inf.meta,
        missing_channels=missing, repeats_basis_m=cfg.repeats_basis_m)
    i = result.critical_node
    mc = m_all[:, i]
    nper = int(min(t.size, 2 ** int(round(np.log2(max(fs * spectral.SEGMENT_S, 8.0))))))
    coef = spectral.dirlik_coefficients(mc)
    entry = {
        "method": cfg.method, "s_n": "stress_life curve, mean stress " + cfg.mean_stress_rule,
        "welch": {"fs_hz": fs, "nperseg": nper, "noverlap": nper // 2, "window": "hann",
                  "detrend": "constant", "scaling": "density"},
        "critical_node": {
            "m0_pa2": mc[0], "m1": mc[1], "m2": mc[2], "m4": mc[3],
            "alpha_1": mc[1] / np.sqrt(mc[0] * mc[2]), "alpha_2": mc[2] / np.sqrt(mc[0] * mc[3]),
            "nu_0_hz": coef["nu_0"], "nu_p_hz": coef["nu_p"],
            **({k: coef[k] for k in ("D1", "D2", "D3", "Q", "R")} if cfg.method == "dirlik"
               else {"b": spectral.tovo_benasciutti_b(mc)})},
    }
    return result, {"spectral": entry}  # numpy scalars: made plain by run_dir.strict_json

