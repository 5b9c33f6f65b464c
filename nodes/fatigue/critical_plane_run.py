"""``equivalent = "findley"``: the critical-plane pass over a history's hot spots.

The block engine ranks every node by its abs-max principal stress life (the equivalent-stress
pass, ``config.RANKING``); the :data:`N_HOT_SPOTS` most damaged nodes are then assessed on
critical planes (:mod:`.critical_plane`, Findley): their six stress components superposed
from the loads batch by batch (:func:`.superposition.stress_history`, held whole: 2.4 kB a
sample for 50 nodes), each node's planes searched and its shear paths counted. The summary's
headline (``min_life_km``, ``critical_node_id``, ...) becomes the smallest Findley life among
them; ``equivalent_pass`` keeps the ranking pass's, ``critical_plane`` the method, its
settings and the hot spots; ``critical_plane.csv`` one row per node assessed.
"""

from __future__ import annotations

import csv
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path

import numpy as np

from .config import FatigueConfig
from .lib import critical_plane as cp
from .lib.damage import cycle_reversals
from .lib.influence_set import InfluenceSet
from .lib.result import FatigueResult
from .lib.superposition import stress_history
from .worker import case_matrix, load_influence

N_HOT_SPOTS = 50
"""Nodes assessed on critical planes: the most damaged of the equivalent-stress pass (a 30 m
Ch 6 run: 6354 samples, ~4 s for the 50)."""
FILE = "critical_plane.csv"


def _life_km(d: float, L: float) -> float:
    return float("inf") if d == 0.0 else L / d / 1000.0


def critical_plane_pass(loads: Iterable[Mapping[str, np.ndarray]], cfg: FatigueConfig,
                        result: FatigueResult, inf: InfluenceSet
                        ) -> tuple[dict, Callable[[Path], None]]:
    """(summary keys, writer of ``critical_plane.csv`` into a folder) of the Findley pass
    over the load batches ``loads`` (channel -> values, as the engine took them)."""
    top = np.argsort(result.damage, kind="stable")[::-1][:N_HOT_SPOTS]
    coef = inf.coefficients[:, top]
    S = np.concatenate([stress_history(case_matrix(inf.case_names, b), coef) for b in loads])
    mat = cfg.material

    def reversals(s: np.ndarray) -> np.ndarray:
        return cycle_reversals(s, -s, mat, cfg.method, "none", cfg.endurance)

    nodes = [cp.findley_node(S[:, i], reversals, residue=cfg.residue) for i in range(top.size)]
    L = result.track_length_m
    dmg = np.array([r.damage for r in nodes])
    order = np.argsort(dmg, kind="stable")[::-1]
    ids = result.node_ids[top]
    xyz = None if result.node_xyz is None else result.node_xyz[top]

    def spot(i: int) -> dict:
        r = nodes[i]
        eq_life = _life_km(float(result.damage[top[i]]), L)
        life = _life_km(r.damage, L)
        return {"node_id": int(ids[i]), "life_km": life, "equivalent_life_km": eq_life,
                "equivalent_over_findley": eq_life / life if np.isfinite(life) else None,
                "normal": r.normal.tolist(), "shear_direction": r.shear_dir.tolist(),
                "rotation_factor": r.rotation_factor, "surface": r.surface}

    crit = int(order[0])
    d = float(dmg[crit])
    repeats = float("inf") if d == 0.0 else 1.0 / d
    extra = {
        "min_life_km": _life_km(d, L), "min_life_repeats": repeats,
        "min_life_repeats_basis": None if result.repeats_basis_m is None
        else _life_km(d, L) * 1000.0 / result.repeats_basis_m,
        "max_damage_per_pass": d, "critical_node_id": int(ids[crit]),
        "critical_node_xyz_m": None if xyz is None else xyz[crit].tolist(),
        "equivalent_pass": {"equivalent": cfg.equivalent, "min_life_km": result.life_km,
                            "critical_node_id": result.critical_node_id},
        "critical_plane": {
            "method": cfg.critical_plane, "k": cp.FINDLEY_K,
            "k_source": f"k = (2 - r) / (2 sqrt(r - 1)), r = f-1/t-1 = 1/"
                        f"{cp.TORSION_TO_BENDING} (Shigley kc torsion; Socie & Marquis "
                        "2000 Ch. 4)",
            "hot_spots_assessed": int(top.size), "step_deg": cp.STEP_DEG,
            "refine_deg": cp.REFINE_DEG,
            "planes": "surface nodes: normal to the surface (least-traction direction); "
                      "else the hemisphere, shear along directions every step_deg",
            "nonproportionality": "rotation_factor: Kanazawa's F = shear range on the "
                                  "plane at 45 deg to the largest-range plane / that range "
                                  "(0 proportional, 1 circular path)",
            "min_life_km": _life_km(d, L), "critical_node_id": int(ids[crit]),
            "normal": nodes[crit].normal.tolist(),
            "shear_direction": nodes[crit].shear_dir.tolist(),
            "hot_spots": [spot(int(i)) for i in order[:10]], "file": FILE},
    }

    def write(folder: Path) -> None:
        with open(folder / FILE, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["node_id", "x_m", "y_m", "z_m", "nx", "ny", "nz", "mx", "my", "mz",
                        "surface", "traction_ratio", "findley_f_max_pa", "damage_per_pass",
                        "life_km", "equivalent_life_km", "rotation_factor"])
            for i in order:
                r = nodes[i]
                p = xyz[i] if xyz is not None else np.full(3, np.nan)
                w.writerow([int(ids[i]), *(f"{v:.6g}" for v in p),
                            *(f"{v:.6f}" for v in r.normal), *(f"{v:.6f}" for v in r.shear_dir),
                            int(r.surface), f"{r.traction_ratio:.3g}", f"{r.f_max:.6e}",
                            f"{r.damage:.6e}", f"{_life_km(r.damage, L):.6e}",
                            f"{_life_km(float(result.damage[top[i]]), L):.6e}",
                            f"{r.rotation_factor:.4f}"])
    return extra, write


def with_critical_planes(loads, cfg: FatigueConfig, result: FatigueResult, extra: dict,
                          files: Callable[[Path], None], say: Callable[[str], None]
                          ) -> Callable[[Path], None]:
    """``equivalent = "findley"``: the critical-plane pass (:func:`critical_plane_pass`) over
    the load batches ``loads``, its summary keys put in ``extra`` and its file written
    after ``files``; else ``files`` as they are."""
    if not cfg.critical_plane:
        return files
    say(f"fatigue: critical planes ({cfg.critical_plane}) at the hot spots")
    more, write = critical_plane_pass(loads, cfg, result, load_influence(cfg))
    extra.update(more)
    extra["outputs"] = [*extra.get("outputs", []), more["critical_plane"]["file"]]

    def both(folder: Path) -> None:
        files(folder)
        write(folder)
    return both
