"""Parametric CAD of the built-in lower arm: a forged H-section wishbone in gmsh/OpenCASCADE.

The parameters are data (``data/lower_arm_cad.toml``, schema in docs/parts.md); the joint
centres are the plant's hardpoints, read through :mod:`cosim.lower_arm` (one definition).

Shape (arm frame: x along the pivot axis, y outward to the ball joint, z up; symmetric about
z = 0, the forging's parting plane):

* **plan**: the convex hull of circles round the two bush eyes and the ball joint, with a
  rounded triangular lightening hole that opens the base, so two legs; the legs end on the
  eye tubes (everything within the eye radius of the pivot axis and behind it cut away);
* **web**: the plan face less the hole, ``section.web`` thick (>= 6 mm: a web thinner than
  about 1/50 of the plan size does not fill in a closed die);
* **ribs** along the outer edge and round the hole (the H's flanges), ``rib_depth_root`` deep
  at the legs' roots, tapering linearly to ``rib_depth_tip`` toward the ball joint (the bending
  moment of the wheel load falls toward the ball joint). ``hole_rib_width`` [m] is one plan width
  or three, one per ``hole_corners`` entry (the hole's outline offset by each corner's own width:
  the rib's width then varies linearly along each side of the hole, so [w_eye, w_eye, w_tip]
  makes the legs' inner flanges wider at their roots on the eyes, where the bending moment is
  largest, and narrower toward the ball joint). Optional eye haunch: ``rib_depth_eye`` [m]
  (default ``rib_depth_root``: no haunch) is the ribs' depth up to ``haunch_y[0]`` [m from the
  pivot axis], tapering linearly to ``rib_depth_root`` at ``haunch_y[1]`` (OCC's fillet pass
  fails on most haunched variants, docs/parts.md);
* **bush eyes**: hollow tubes along x (the pivot axis), bore = the bushes' outer sleeves;
  with ``[bush_eye] pivot_tube`` one tube from eye to eye (closing the triangle), its bore
  ``pivot_tube_bore`` between the eyes entered by 15-degree cones;
* **ball-joint housing**: a vertical ring with a through bore for the joint's cartridge;
* **damper seat and bump-stop pad**: round bosses on the legs;
* **fillets**, in ONE OpenCASCADE pass on the solid before its bores are cut: radius
  ``section.fillet`` (>= 5 mm) on every sharp re-entrant edge in the web's planes (where a
  rib, an eye or the housing meets the web), ``section.junction_fillet`` (default: the same)
  on the other sharp re-entrant edges (ribs meeting the eye tubes and the housing). OCC
  refuses a second pass (a fillet cannot end on a fillet face), and the same pass with the
  bores already cut returned an invalid solid (measured: docs/parts.md); the bores lie
  inside the tubes, away from every fillet, so cutting them after changes no fillet.

Lengths in metres. :func:`build` leaves the solid in the current gmsh model and returns the
tags of the fillet faces (for mesh refinement).
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from cosim import lower_arm as geo
from cosim.errors import InputFileError

DATA = Path(__file__).parent / "data"
DEFAULT_PARAMS = DATA / "lower_arm_cad.toml"


def load_params(path: Path = DEFAULT_PARAMS) -> dict[str, Any]:
    """The CAD parameters (TOML) as nested dicts; a missing table or key is an
    `InputFileError` naming it."""
    try:
        with open(path, "rb") as fh:
            p = tomllib.load(fh)
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise InputFileError(str(path), str(exc)) from None
    need = {"plan": ("bush_boss_radius", "ball_joint_boss_radius", "hole_corners",
                     "hole_corner_radii"),
            "section": ("web", "outer_rib_width", "hole_rib_width", "rib_depth_root",
                        "rib_depth_tip", "taper_y", "fillet"),
            "bush_eye": ("outer_radius", "bore_radius", "length"),
            "ball_joint": ("outer_radius", "bore_radius", "depth")}
    for table, keys in need.items():
        for k in keys:
            if k not in p.get(table, {}):
                raise InputFileError(str(path), f"missing key [{table}] {k}")
    s = p["section"]
    if s["web"] < 0.006 - 1e-12:
        raise InputFileError(str(path), f"[section] web = {s['web']}: a forging needs >= 0.006 m")
    if s["fillet"] < 0.005 - 1e-12:
        raise InputFileError(str(path), f"[section] fillet = {s['fillet']}: expected >= 0.005 m")
    w = np.atleast_1d(np.asarray(s["hole_rib_width"], dtype=float))
    if w.ndim != 1 or len(w) not in (1, len(p["plan"]["hole_corners"])) or np.any(w <= 0.0):
        raise InputFileError(str(path), f"[section] hole_rib_width = {s['hole_rib_width']}: "
                             "expected one positive width or one per hole corner [m]")
    if "rib_depth_eye" in s and "haunch_y" not in s:
        raise InputFileError(str(path), "[section] rib_depth_eye needs haunch_y = [y_a, y_b]")
    rj = s.get("junction_fillet", s["fillet"])
    if not 0.001 <= rj <= s["fillet"] + 1e-12:
        raise InputFileError(str(path), f"[section] junction_fillet = {rj}: expected "
                             f"0.001 m to the fillet ({s['fillet']} m)")
    return p


def _hull_face(centres: np.ndarray, radii: np.ndarray, z: float = 0.0) -> int:
    """A plane face (tag) bounded by the convex hull of circles given counter-clockwise:
    outer tangent lines joined by arcs (every circle on the hull)."""
    from gmsh import model  # type: ignore[import-untyped]

    occ = model.occ
    n = len(centres)
    tangents = []  # (p_on_i, p_on_j) for the edge i -> i+1
    for i in range(n):
        j = (i + 1) % n
        c1, c2, r1, r2 = centres[i], centres[j], radii[i], radii[j]
        d = c2 - c1
        L = float(np.hypot(*d))
        d = d / L
        n0 = np.array([d[1], -d[0]])  # right of the edge: outward for a CCW polygon
        s = (r1 - r2) / L
        nrm = math.sqrt(1.0 - s * s) * n0 + s * d
        tangents.append((c1 + r1 * nrm, c2 + r2 * nrm))
    A = [occ.addPoint(a[0], a[1], z) for a, _ in tangents]
    B = [occ.addPoint(b[0], b[1], z) for _, b in tangents]
    tags = []
    for i in range(n):
        j = (i + 1) % n
        tags.append(occ.addLine(A[i], B[i]))
        pc = occ.addPoint(centres[j][0], centres[j][1], z)
        tags.append(occ.addCircleArc(B[i], pc, A[j]))
    loop = occ.addCurveLoop(tags)
    return int(occ.addPlaneSurface([loop]))


def _ccw(points: np.ndarray) -> np.ndarray:
    """Indices ordering points counter-clockwise about their mean."""
    c = points.mean(axis=0)
    return np.argsort(np.arctan2(points[:, 1] - c[1], points[:, 0] - c[0]))


def _slab(face_tag: int, z0: float, z1: float) -> list[tuple[int, int]]:
    from gmsh import model  # type: ignore[import-untyped]

    occ = model.occ
    occ.translate([(2, face_tag)], 0, 0, z0)
    out = occ.extrude([(2, face_tag)], 0, 0, z1 - z0)
    return [e for e in out if e[0] == 3]


def build(params: dict[str, Any], fillet: bool = True) -> dict[str, list[int]]:
    """Build the arm as one OCC volume in the current gmsh model (gmsh initialised by the
    caller). Returns {"volume": [tag], "fillets": [face tags]}; with ``fillet=False`` the
    unfilleted solid ({"volume": [tag], "fillets": [], "root_curves": []}: for the fillet
    experiments of python -m bench arm-fillet-order)."""
    from gmsh import model  # type: ignore[import-untyped]

    occ = model.occ
    pl, sec = params["plan"], params["section"]
    eye, bj = params["bush_eye"], params["ball_joint"]
    hp = {k: np.asarray(v, dtype=float) for k, v in geo.HARDPOINTS.items()}
    centres = np.array([hp["bush_front"][:2], hp["ball_joint"][:2], hp["bush_rear"][:2]])
    radii = np.array([pl["bush_boss_radius"], pl["ball_joint_boss_radius"],
                      pl["bush_boss_radius"]])
    order = _ccw(centres)
    centres, radii = centres[order], radii[order]
    hole = np.asarray(pl["hole_corners"], dtype=float)
    rh = np.asarray(pl["hole_corner_radii"], dtype=float)
    k = _ccw(hole)
    hole, rh = hole[k], rh[k]
    w_out = float(sec["outer_rib_width"])
    w_hole = np.broadcast_to(np.asarray(sec["hole_rib_width"], dtype=float), (len(hole),))[k]
    t = float(sec["web"])
    D0, D1 = float(sec["rib_depth_root"]), float(sec["rib_depth_tip"])
    De = float(sec.get("rib_depth_eye", D0))

    L, ro = float(eye["length"]), float(eye["outer_radius"])
    b = hp["ball_joint"]
    # web: plan less hole (the hole opens the base: no member between the eyes)
    plan = _hull_face(centres, radii)
    hole_f = _hull_face(hole, rh)
    web_face, _ = occ.cut([(2, plan)], [(2, hole_f)])
    web = _slab(web_face[0][1], -t / 2, t / 2)
    # rib bands: outline less the outline offset inward (less the hole); hole offset
    # outward less the hole (within the outline)
    plan2 = _hull_face(centres, radii)
    inner = _hull_face(centres, radii - w_out)
    band_out, _ = occ.cut([(2, plan2)], [(2, inner), (2, _hull_face(hole, rh))])
    hole_o = _hull_face(hole, rh + w_hole)
    hole_i = _hull_face(hole, rh)
    band_hole, _ = occ.cut([(2, hole_o)], [(2, hole_i)])
    band_hole, _ = occ.intersect(band_hole, [(2, _hull_face(centres, radii))])
    ribs = []
    Dmax = max(D0, De)
    for f in band_out + band_hole:
        ribs += _slab(f[1], -Dmax / 2, Dmax / 2)
    # taper envelope: a prism along x whose (y, z) section follows the rib depth
    y0, y1 = (float(v) for v in sec["taper_y"])
    ylo, yhi = -0.2, 0.6
    half = [(ylo, D0 / 2), (y0, D0 / 2), (y1, D1 / 2), (yhi, D1 / 2)]
    if De != D0:  # the eye haunch: De up to haunch_y[0], linear to D0 at haunch_y[1]
        ya, yb = (float(v) for v in sec["haunch_y"])
        half = [(ylo, De / 2), (ya, De / 2), (yb, D0 / 2)] + half[1:]
        half = [q for i, q in enumerate(half) if i == 0 or abs(q[0] - half[i - 1][0]) > 1e-9]
    prof = [(y, -z) for y, z in half] + [(y, z) for y, z in reversed(half)]
    pts = [occ.addPoint(-0.4, y, z) for y, z in prof]
    lines = [occ.addLine(pts[i], pts[(i + 1) % len(pts)]) for i in range(len(pts))]
    env_face = occ.addPlaneSurface([occ.addCurveLoop(lines)])
    env = occ.extrude([(2, env_face)], 0.8, 0, 0)
    env_vol = [e for e in env if e[0] == 3]
    ribs_cut, _ = occ.intersect(ribs, env_vol)
    body, _ = occ.fuse(web, ribs_cut)
    # the legs end on the eyes' outer cylinders: clear everything within ro of the pivot axis
    axis_cyl = [(3, occ.addCylinder(-0.5, 0.0, 0.0, 1.0, 0, 0, ro)),
                (3, occ.addBox(-0.5, -0.5, -0.5, 1.0, 0.5, 1.0))]  # and all behind the axis
    body, _ = occ.cut(body, axis_cyl)
    xs = sorted((hp["bush_front"][0], hp["bush_rear"][0]))
    if eye.get("pivot_tube", False):  # one tube along the pivot axis from eye to eye
        tubes = [(3, occ.addCylinder(xs[0] - L / 2, 0.0, 0.0, xs[1] - xs[0] + L, 0, 0, ro))]
    else:
        tubes = [(3, occ.addCylinder(hp[n][0] - L / 2, hp[n][1], hp[n][2], L, 0, 0, ro))
                 for n in ("bush_front", "bush_rear")]
    housing = [(3, occ.addCylinder(b[0], b[1], -bj["depth"] / 2, 0, 0, bj["depth"],
                                   bj["outer_radius"]))]
    solid, _ = occ.fuse(body, tubes + housing)
    occ.synchronize()
    vols = [e[1] for e in solid if e[0] == 3]
    if len(vols) != 1:
        raise RuntimeError(f"the arm CAD gave {len(vols)} volumes, expected 1")
    root_curves: list[int] = []
    fillets: list[int] = []
    if fillet:
        # One fillet pass on the solid WITHOUT its bores: OpenCASCADE refuses a second pass
        # (a fillet cannot end on a fillet face) and, with the bores cut first, returned an
        # invalid solid (the pivot tube's bore filled, docs/parts.md). The bores are cut
        # after, away from every fillet.
        vols, root_curves, sharp_pts = _fillet_all(vols[0], sec)
    solid, _ = occ.cut([(3, vols[0])], _bores(params, hp, xs))
    occ.synchronize()
    vols = [e[1] for e in solid if e[0] == 3]
    if len(vols) != 1:
        raise RuntimeError(f"the arm CAD gave {len(vols)} volumes after its bores, expected 1")
    if fillet:
        fillets = _fillet_faces(vols[0], sharp_pts)
    return {"volume": vols, "fillets": fillets, "root_curves": root_curves}


def _bores(params: dict[str, Any], hp: dict[str, np.ndarray],
           xs: list[float]) -> list[tuple[int, int]]:
    """The tools cutting the bores: the bushes' outer sleeves, the ball joint's cartridge and
    (pivot tube) the thinner wall between the eyes, entered by 15-degree cones (a square step
    there would be a sharp re-entrant edge, features.py; a 165-degree one is not)."""
    from gmsh import model  # type: ignore[import-untyped]

    occ = model.occ
    sec, eye, bj = params["section"], params["bush_eye"], params["ball_joint"]
    L, ro = float(eye["length"]), float(eye["outer_radius"])
    b = hp["ball_joint"]
    zmax = 0.5 * max(sec["rib_depth_root"], sec.get("rib_depth_eye", 0.0), sec["rib_depth_tip"],
                     2 * ro, bj["depth"]) + 0.01
    rb = float(eye["bore_radius"])
    if eye.get("pivot_tube", False):
        bores = [(3, occ.addCylinder(xs[0] - L / 2 - 0.01, 0.0, 0.0, xs[1] - xs[0] + L + 0.02,
                                     0, 0, rb))]
    else:
        bores = [(3, occ.addCylinder(hp[n][0] - L / 2 - 0.01, hp[n][1], hp[n][2], L + 0.02,
                                     0, 0, rb)) for n in ("bush_front", "bush_rear")]
    bores.append((3, occ.addCylinder(b[0], b[1], -zmax, 0, 0, 2 * zmax, bj["bore_radius"])))
    pb = eye.get("pivot_tube_bore")
    if eye.get("pivot_tube", False) and pb is not None and float(pb) > rb:
        pb = float(pb)
        cone = (pb - rb) / math.tan(math.radians(15.0))
        x0, x1 = xs[0] + L / 2, xs[1] - L / 2
        bores.append((3, occ.addCylinder(x0 + cone, 0.0, 0.0, x1 - x0 - 2 * cone, 0, 0, pb)))
        bores.append((3, occ.addCone(x0, 0.0, 0.0, cone, 0, 0, rb, pb)))
        bores.append((3, occ.addCone(x1, 0.0, 0.0, -cone, 0, 0, rb, pb)))
    return bores


def _fillet_all(vol: int, sec: dict[str, Any]) -> tuple[list[int], list[int], np.ndarray]:
    """Fillet every sharp re-entrant edge of ``vol`` in one OCC pass: the web roots (in the
    web's planes z = +-t/2) at ``fillet``, the rest (ribs meeting the eye tubes and the
    housing) at ``junction_fillet`` (default ``fillet``). Returns (volumes, root curves,
    points [m] along every edge filleted, (k, 3): to find the fillet faces after the bores)."""
    from gmsh import model  # type: ignore[import-untyped]

    from .features import sharp_reentrant_edges

    occ = model.occ
    t, r = float(sec["web"]), float(sec["fillet"])
    rj = float(sec.get("junction_fillet", r))
    roots: list[int] = []
    other: list[int] = []
    pts: list[np.ndarray] = []
    for e in sharp_reentrant_edges(vol):
        z = e["points_m"][:, 2]
        (roots if np.all(np.abs(np.abs(z) - t / 2) < 1e-6) else other).append(e["curve"])
        pts.append(_dense_points(e["curve"]))
    curves = roots + other
    out = occ.fillet([vol], curves, [r] * len(roots) + [rj] * len(other))
    occ.synchronize()
    vols = [e[1] for e in out if e[0] == 3]
    if len(vols) != 1 or occ.getMass(3, vols[0]) <= 0.0:
        raise RuntimeError(f"the arm's fillet pass gave volumes {vols}: an invalid solid")
    return vols, roots, np.vstack(pts) if pts else np.zeros((0, 3))


def _dense_points(curve: int, n: int = 101) -> np.ndarray:
    from gmsh import model  # type: ignore[import-untyped]

    lo, hi = model.getParametrizationBounds(1, curve)
    us = np.linspace(lo[0], hi[0], n)
    return np.asarray(model.getValue(1, curve, list(us))).reshape(-1, 3)


def _fillet_faces(vol: int, sharp_pts: np.ndarray) -> list[int]:
    """The fillet faces of the filleted solid: its non-plane faces whose parametric centre
    lies within 0.6 mm + the largest fillet radius of an edge filleted away (a 90-degree
    fillet's mid-surface is 0.41 r from the edge it replaced)."""
    from gmsh import model  # type: ignore[import-untyped]

    if len(sharp_pts) == 0:
        return []
    out = []
    for _, s in model.getBoundary([(3, vol)], combined=False, oriented=False):
        s = abs(s)
        if model.getType(2, s) == "Plane":
            continue
        lo, hi = model.getParametrizationBounds(2, s)
        c = np.asarray(model.getValue(2, s, [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])]))
        d = np.min(np.linalg.norm(sharp_pts - c, axis=1))
        if d < 0.006:
            out.append(s)
    return out
