"""A part's model card: mass, centre of mass, first flexible modes with a shape label,
static and 3 g stresses, hot spots (and whether one sits on a sharp re-entrant edge), the
joint-zone rule, the mesh convergence table. Pure numerics; ``orchestrator/studies/
part_check.py`` prints it.

Mode labels (:func:`label_mode`): the part's principal axes (inertia tensor): the **normal**
n (largest moment: a plate-like part's out-of-plane axis), the **long** axis a (smallest) and
the transverse b. A mode whose displacement is mostly along n is out of plane: its n
displacement w(a, b) is fitted by a quadratic; the twist term a·b dominating gives
"torsion", the a², b² terms "vertical bending" (the names of the arm, whose n is the body's
vertical); a mode mostly in the plane is "in-plane bending", mostly along a "axial"; a fit
explaining < 50 % of w is "higher-order or local" (a second bending, an eye).

Convergence (:func:`convergence`): the ten hot spots are the ten assessed nodes of highest
von Mises stress under the static load set on the finest mesh (the ten "most damaged" by the
static + 3 g cases, which scale together; not a damage ranking from a run). On every mesh each
unit case's stress tensor is interpolated at the spots' physical points (the P2 field of the
nodal-averaged stresses in the tetrahedron containing the point, or, for a point just outside
a coarser faceted surface, at a point of the nearest tetrahedron's surface near it: the gap
is reported), and its von Mises stress taken; the change between the two finest meshes is per
spot the largest over the cases of |Δσ| / (the spot's largest unit-case stress).

With ``mesh.convergence_local`` (local refinement, affordable where a global refinement is
not): the first mesh is the global one at the finest ``mesh.convergence`` size; every
assessed node whose static stress there is at least ``REFINE_FRACTION`` of its hot spot gets
a ball of ``mesh.convergence_radius`` round it (greedily, centres at least half a radius
apart, so every such node lies within half a radius of a centre), and each further mesh is
the same global mesh with the element size ``convergence_local[i]`` inside those balls. The
table then says whether the finest mesh's ten hot spots lie inside the refined region and the
highest assessed stress outside it (which the refinement did not test).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from ..lib.equivalent_stress import von_mises
from .build import PartModel, part_model, solve_part
from .schema import Part

N_HOT = 10
REFINE_FRACTION = 0.7
"""Nodes at or above this share of the hot spot's static stress are refined locally."""
DAMAGE_FRACTION = 0.1
"""With a damage function: the global mesh's nodes at or above this share of its peak damage
are refined too (damage ~ stress^k, k ~ 5-10: about 0.7-0.8 of the stress)."""
MAX_BALLS = 64
ZONE_RULE = ("a surface node is assessed unless it lies within its joint's zone (distance "
             "[m], per joint below) of any node of that joint's coupling: there the stress is "
             "the idealised load introduction's, not the pressed-in sleeve's or cartridge's")


def label_mode(xyz: np.ndarray, u: np.ndarray, inertia: np.ndarray,
               com: np.ndarray) -> str:
    """Shape label of a mode (displacements u (n, 3) at nodes xyz (n, 3))."""
    # the long, transverse, normal unit axes: smallest, middle, largest principal moment
    a_ax, b_ax, n_ax = np.linalg.eigh(np.asarray(inertia))[1].T
    r = xyz - com
    a, b = r @ a_ax, r @ b_ax
    a, b = a / np.abs(a).max(), b / np.abs(b).max()
    e = np.array([np.sum((u @ ax) ** 2) for ax in (a_ax, b_ax, n_ax)])
    e /= e.sum()
    if e[2] < 0.5:
        return "axial" if e[0] > 0.7 else "in-plane bending"
    w = u @ n_ax
    X = np.c_[np.ones_like(a), a, b, a * a, b * b, a * b]
    c, *_ = np.linalg.lstsq(X, w, rcond=None)
    fit = X @ c
    r2 = 1.0 - np.sum((w - fit) ** 2) / max(np.sum((w - w.mean()) ** 2), 1e-300)
    if r2 < 0.5:
        return "higher-order or local"
    twist = np.var(c[5] * a * b)
    bend = np.var(c[3] * a * a + c[4] * b * b)
    return "torsion" if twist > bend else "vertical bending"


def _hot_spots(pm: PartModel, coef: np.ndarray, f: np.ndarray, labels: np.ndarray,
               n: int = N_HOT) -> tuple[list[dict], np.ndarray]:
    S = np.einsum("c,cnk->nk", f, coef)
    vm = von_mises(S)
    idx = np.argsort(np.where(pm.assessed, vm, -1.0))[::-1][:n]
    sharp = pm.mesh.sharp_edges
    tree = cKDTree(sharp) if sharp.shape[0] else None
    out = []
    for i in idx:
        d = float(tree.query(pm.fe.node_xyz[i])[0]) if tree is not None else float("inf")
        out.append({"node": int(labels[i]), "index": int(i),
                    "xyz_m": [float(v) for v in pm.fe.node_xyz[i]],
                    "von_mises_mpa": float(vm[i]) / 1e6,
                    "distance_to_sharp_edge_m": d,
                    "on_sharp_reentrant_edge": bool(d < pm.fillet_size)})
    return out, vm


def card(part: Part, loads: Mapping[str, float] | None, mesh_size: float | None = None,
         n_modes: int = 6) -> tuple[dict[str, Any], PartModel, dict]:
    """The model card (dict; MPa where a key says so), the model and the full-field
    results. ``loads``: the static joint loads [N, N m] by channel (the plant's)."""
    pm = part_model(part, mesh_size)
    inf, ex = solve_part(pm, n_modes)
    meta = inf.meta
    mp = pm.fe.mass_properties()
    shapes = ex["shapes"]
    labels_m = []
    if shapes is not None:
        for k in range(shapes.shape[1]):
            u = shapes[:, k][pm.fe.node_dofs]
            labels_m.append(label_mode(pm.fe.node_xyz, u, np.asarray(mp["inertia"]),
                                       np.asarray(mp["centre_of_mass"])))
    c: dict[str, Any] = {
        "part": part.name, "file": str(part.path), "geometry": part.geometry,
        "material": part.material.name, "yield_mpa": part.material.Sy / 1e6,
        "mass_kg": meta["mass_kg"], "solid_mass_kg": meta["solid_mass_kg"],
        "hardware_mass_kg": meta["hardware_mass_kg"],
        "centre_of_mass_m": meta["centre_of_mass_m"],
        "modes": [{"hz": f, "shape": s} for f, s in
                  zip(meta["natural_frequencies_hz"], labels_m, strict=True)],
        "mesh_size_m": pm.mesh_size, "fillet_size_m": pm.fillet_size,
        "n_elements": meta["n_elements"], "n_nodes": meta["n_nodes"],
        "n_nodes_assessed": meta["n_surface_nodes_analysed"], "element": meta["element"],
        "supports": meta["supports"], "load_cases": list(inf.case_names),
        "joint_zone_rule": ZONE_RULE, "joints": meta["joints"],
        "sharp_reentrant_edge_points": int(pm.mesh.sharp_edges.shape[0]),
        "fillet_faces": pm.mesh.fillet_faces,
    }
    names = list(inf.case_names)
    used = {k: v for k, v in (loads or {}).items() if k in names}
    if used:
        f = np.array([used.get(n, 0.0) for n in names])
        hot, vm = _hot_spots(pm, ex["coef"], f, ex["labels"])
        zone = ~pm.assessed
        c.update({
            "static_loads": used,
            "static_hotspot_stress_mpa": hot[0]["von_mises_mpa"],
            "max_stress_3g_mpa": 3.0 * hot[0]["von_mises_mpa"],
            "ratio_3g_to_yield": 3.0 * hot[0]["von_mises_mpa"] * 1e6 / part.material.Sy,
            "hot_spots": hot,
            "static_joint_zone_peak_mpa": float(vm[zone].max()) / 1e6 if zone.any() else None,
            "hot_spot_on_sharp_reentrant_edge": any(h["on_sharp_reentrant_edge"] for h in hot),
        })
    return c, pm, ex


def p2_interpolation(pm: PartModel, pts: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """How to interpolate a nodal field of ``pm``'s P2 mesh at physical points (k, 3):
    (node indices (k, 10), weights (k, 10), gap (k,) [m] between each point and where it is
    evaluated: 0 inside the mesh; a point outside (a coarser mesh's faceted curved surface)
    is taken in the candidate tetrahedron it is most nearly inside, at its barycentric
    coordinates clamped to >= 0: a point of that tetrahedron's surface near it)."""
    fe = pm.fe
    p, t = fe.mesh.p.T, fe.mesh.t.T  # (nv, 3), (ne, 4)
    edofs = fe.sbasis.element_dofs.T  # (ne, 10): P2 dofs (node indices of fe.node_xyz)
    ne = t.shape[0]
    v2t = sp.csr_matrix((np.ones(4 * ne), (t.ravel(), np.repeat(np.arange(ne), 4))),
                        shape=(p.shape[0], ne))
    _, near = cKDTree(p).query(pts, k=min(12, p.shape[0]))
    nodes = np.zeros((len(pts), 10), dtype=np.int64)
    w = np.zeros((len(pts), 10))
    gap = np.zeros(len(pts))

    def bary(e: int, x: np.ndarray) -> np.ndarray:
        v = p[t[e]]
        lam = np.linalg.solve((v[1:] - v[0]).T, (np.atleast_2d(x) - v[0]).T).T
        return np.c_[1.0 - lam.sum(axis=1), lam]

    for k, x in enumerate(pts):
        cand = np.unique(v2t[near[k]].indices)
        lams = np.vstack([bary(e, x) for e in cand])
        best = int(np.argmax(lams.min(axis=1)))
        e, lam = int(cand[best]), lams[best]
        if lam.min() < 0.0:
            lam = np.maximum(lam, 0.0)
            lam /= lam.sum()
            gap[k] = float(np.linalg.norm(lam @ p[t[e]] - x))
        mu = bary(e, fe.node_xyz[edofs[e]])  # each P2 node's own barycentric coordinates
        for a in range(10):
            big = np.nonzero(mu[a] > 0.25)[0]
            if big.size == 1:  # vertex node
                i_ = big[0]
                w[k, a] = lam[i_] * (2.0 * lam[i_] - 1.0)
            else:  # edge midpoint
                w[k, a] = 4.0 * lam[big[0]] * lam[big[1]]
        nodes[k] = edofs[e]
    return nodes, w, gap


def _refine_balls(pm: PartModel, vm: np.ndarray, radius: float, size: float,
                  fraction: float = REFINE_FRACTION, extra: np.ndarray | None = None
                  ) -> tuple[list[tuple], bool]:
    """Refinement balls round the assessed nodes at or above ``fraction`` of the assessed
    peak and round the nodes ``extra`` (indices, e.g. the most damaged, in order) (greedy,
    centres >= radius / 2 apart; the first ``N_HOT`` of each before the rest); (balls, capped
    at MAX_BALLS)."""
    a = np.nonzero(pm.assessed)[0]
    a = a[np.argsort(vm[a])[::-1]]
    a = a[vm[a] >= fraction * vm[a[0]]]
    if extra is not None:  # the ten of each first: the cap must not drop the damaged
        e = np.asarray(extra, dtype=np.int64)
        a = np.r_[a[:N_HOT], e[:N_HOT], a[N_HOT:], e[N_HOT:]]
    centres: list[np.ndarray] = []
    for i in a:
        x = pm.fe.node_xyz[i]
        if all(np.linalg.norm(x - c) >= 0.5 * radius for c in centres):
            centres.append(x)
            if len(centres) == MAX_BALLS:
                return [(*map(float, c), radius, size) for c in centres], True
    return [(*map(float, c), radius, size) for c in centres], False


def _unit_at(pm: PartModel, coef: np.ndarray, pts: np.ndarray, f: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-case von Mises stress (cases, k) of the unit cases at points pts (k, 3), the
    static set's (k,) there, and the interpolation gaps (k,)."""
    nodes, w, gap = p2_interpolation(pm, pts)
    unit = np.stack([von_mises(np.einsum("kj,kjc->kc", w, coef[k][nodes]))
                     for k in range(coef.shape[0])])
    static = von_mises(np.einsum("kj,kjc->kc", w, np.einsum("c,cnk->nk", f, coef)[nodes]))
    return unit, static, gap


def _change(per_mesh: list[np.ndarray]) -> list[float] | None:
    """Per point: max over the cases of |change| between the two finest meshes / the
    point's largest unit-case stress on the finest."""
    if len(per_mesh) < 2:
        return None
    a_, b_ = per_mesh[-2], per_mesh[-1]
    ref = np.maximum(b_.max(axis=0), 1e-30)
    return (np.abs(a_ - b_).max(axis=0) / ref).tolist()


def convergence(part: Part, sizes: Sequence[float], loads: Mapping[str, float],
                local_sizes: Sequence[float] | None = None,
                radius: float | None = None,
                log: Callable[[str], None] | None = None,
                damage: Callable[[Any], np.ndarray] | None = None,
                damage_fraction: float = DAMAGE_FRACTION) -> dict:
    """The convergence table (module docstring), finest last. ``local_sizes`` / ``radius``
    default to the part file's ``mesh.convergence_local`` / ``convergence_radius``; without
    local sizes the meshes are the global ``sizes``. ``log``: called with a line per mesh
    solved (size, nodes, static hot spot, wall time). ``damage``: a function of a mesh's
    `InfluenceSet` giving each of its nodes' damage (a run's fatigue pass); with it the
    refinement also takes in the global mesh's nodes at or above ``damage_fraction`` of its
    peak damage, and the table the finest mesh's ten most damaged nodes (``damaged``)."""
    import time

    local = list(part.convergence_local if local_sizes is None else local_sizes)
    radius = float(part.convergence_radius if radius is None else radius)
    sizes = sorted((float(s) for s in sizes), reverse=True)
    runs = []
    balls: list[tuple] = []
    capped = False
    names: list[str] = []
    if local:
        s0 = sizes[-1]
        levels = [(s0, None)] + [(s0, float(h)) for h in sorted(local, reverse=True)]
    else:
        levels = [(s, None) for s in sizes]
    for s, h in levels:
        t0 = time.perf_counter()
        pm = part_model(part, s, refine=[b[:4] + (h,) for b in balls] if h else ())
        t1 = time.perf_counter()
        inf, ex = solve_part(pm, n_modes=0 if h else 1)  # local refinement: mode as global
        t2 = time.perf_counter()
        names = list(inf.case_names)
        f = np.array([loads.get(n, 0.0) for n in names])
        vm = von_mises(np.einsum("c,cnk->nk", f, ex["coef"]))
        dmg = None
        if damage is not None:
            dmg = np.zeros(pm.fe.n_nodes)
            dmg[np.nonzero(pm.assessed)[0]] = np.asarray(damage(inf), dtype=float)
        if local and not balls:
            extra = None
            if dmg is not None:
                order = np.argsort(dmg)[::-1]
                extra = order[dmg[order] >= damage_fraction * dmg[order[0]]]
            balls, capped = _refine_balls(pm, vm, radius, float(local[0]), extra=extra)
        runs.append((pm, inf, ex, vm, s, h, dmg))
        if log is not None:
            f1 = (inf.meta["natural_frequencies_hz"] or [float("nan")])[0]
            log(f"mesh {s * 1e3:.1f} mm, local {'-' if h is None else f'{h * 1e3:.1f} mm'}: "
                f"{pm.fe.n_nodes} nodes, {int(pm.assessed.sum())} assessed, mode 1 "
                f"{f1:.0f} Hz, static hot spot {float(vm[pm.assessed].max()) / 1e6:.1f} MPa"
                + ("" if dmg is None else f", peak damage {dmg.max():.4g}")
                + f"; mesh {t1 - t0:.0f} s, solve {t2 - t1:.0f} s"
                + ("" if dmg is None else f", damage {time.perf_counter() - t2:.0f} s")
                + (f"; {len(balls)} balls" if balls else ""))
    pm_f, inf_f, ex_f, vm_f, _, _, dmg_f = runs[-1]  # f: the finest mesh's loads
    hot, _ = _hot_spots(pm_f, ex_f["coef"], f, ex_f["labels"])
    spots = np.array([h["xyz_m"] for h in hot])
    dspots = None
    if dmg_f is not None:
        di = np.argsort(np.where(pm_f.assessed, dmg_f, -1.0))[::-1][:N_HOT]
        dspots = pm_f.fe.node_xyz[di]
    rows, per_mesh, per_mesh_d = [], [], []
    for pm, inf, ex, vm, s, h, dmg in runs:
        unit, static, gap = _unit_at(pm, ex["coef"], spots, f)
        per_mesh.append(unit)
        row = {"size_m": s, "local_size_m": h, "fillet_size_m": pm.fillet_size,
               "n_elements": int(pm.mesh.t.shape[0]),
               "n_nodes": int(pm.fe.n_nodes),
               "n_assessed": int(pm.assessed.sum()),
               "mass_kg": inf.meta["mass_kg"],
               "mode_1_hz": (inf.meta["natural_frequencies_hz"] or [float("nan")])[0],
               "static_hotspot_mpa": float(vm[pm.assessed].max()) / 1e6,
               "static_at_spots_mpa": [float(v) / 1e6 for v in static],
               "interpolation_gap_max_m": float(gap.max())}
        if dspots is not None and dmg is not None:
            unit_d, static_d, gap_d = _unit_at(pm, ex["coef"], dspots, f)
            per_mesh_d.append(unit_d)
            row.update({"peak_damage": float(dmg.max()),
                        "peak_damage_xyz_m": [float(v) for v in
                                              pm.fe.node_xyz[int(np.argmax(dmg))]],
                        "static_at_damaged_mpa": [float(v) / 1e6 for v in static_d],
                        "interpolation_gap_damaged_max_m": float(gap_d.max())})
        rows.append(row)
    change = _change(per_mesh)
    out: dict[str, Any] = {"rows": rows, "hot_spots": hot, "unit_change_two_finest": change,
                           "max_unit_change_two_finest": None if change is None
                           else max(change)}
    if dspots is not None and dmg_f is not None:
        ch_d = _change(per_mesh_d)
        out["damaged"] = [{"node": int(ex_f["labels"][i]), "index": int(i),
                           "xyz_m": [float(v) for v in pm_f.fe.node_xyz[i]],
                           "damage": float(dmg_f[i]),
                           "static_von_mises_mpa": float(vm_f[i]) / 1e6} for i in di]
        out["unit_change_two_finest_damaged"] = ch_d
        out["max_unit_change_two_finest_damaged"] = None if ch_d is None else max(ch_d)
    if local:
        c = np.array([b[:3] for b in balls])
        d_spot = cKDTree(c).query(spots)[0]
        d_all = cKDTree(c).query(pm_f.fe.node_xyz)[0]
        outside = pm_f.assessed & (d_all > radius)
        out["refinement"] = {
            "radius_m": radius, "fraction": REFINE_FRACTION, "n_balls": len(balls),
            "capped": capped, "centres_m": c.tolist(),
            "hot_spots_inside": bool(np.all(d_spot <= radius)),
            "peak_outside_mpa": float(vm_f[outside].max()) / 1e6 if outside.any() else None,
            "tenth_hot_spot_mpa": hot[-1]["von_mises_mpa"]}
        if dspots is not None and dmg_f is not None:
            out["refinement"].update({
                "damage_fraction": damage_fraction,
                "damaged_inside": bool(np.all(cKDTree(c).query(dspots)[0] <= radius)),
                "peak_damage_outside": float(dmg_f[outside].max()) if outside.any()
                else None})
    return out
