"""Stress influence coefficients c_i (Pa per unit load) of the lower arm: built in or imported.

An `InfluenceSet` holds, for n load cases and m nodes, the six stress components per unit
load: ``coefficients[i, node, :] = (σx, σy, σz, τxy, τyz, τzx)`` in Pa/N (Pa/(N m) for a unit
moment), with the name of the load channel each case answers to (``ball_joint_z`` answers to
the column ``plant/arm/ball_joint_z``).

* `builtin_influence`: the FE arm (`arm_mesh`, `arm_fe`; geometry `cosim.lower_arm`), every
  joint load as a unit case (`BUILTIN_CASES`), the free arm supported by inertia relief;
  cached on disk under ``$SUSCOSIM_CACHE`` (default ``~/.cache/suscosim``) keyed by a hash of
  geometry, mesh and material.
* `import_influence`: per-case CSV tables exported from a commercial FE code (thesis App V:
  one file per unit load case, one row per node, columns Sx Sy Sz Sxy Syz Szx), with the
  scenario's mapping of load channels to files (and a scale/sign per channel, for axis
  conventions that differ between the MBS and FE codes).
"""

from __future__ import annotations

import csv
import hashlib
import json
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from cosim import lower_arm as geo
from cosim.errors import InputFileError, ScenarioError
from cosim.safe_open import open_user_text

from .material import Material
from .prnsol import looks_like_prnsol, read_prnsol

CACHE_VERSION = "arm-fe-v2"
AXES = ("x", "y", "z")
FORCE_POINTS = ("ball_joint", "damper_mount", "bush_front", "bush_rear")
"""Joints whose three force components are unit cases (arm frame, N)."""
BUILTIN_CASES = tuple(f"{p}_{a}" for p in FORCE_POINTS for a in AXES) + (
    "torsion_bar_mx", "bump_stop_y", "bump_stop_z")
"""Every joint load of the arm as a unit case (names = the ``plant/arm`` fields): 3 forces at
the ball joint, the damper seat and each bush, the torsion-spring moment about the pivot axis
x [N m] (through the pivot: half at each bush eye, as the thesis's FE divided its revolute
joint's loads between nodes A and B, Ch 6.2), and the bump-stop force at its pad (y and z:
the bumper pushes along the body's vertical, which the turned arm sees partly along its y)."""
SUPPORT_POINTS = ("bush_front", "bush_rear", "ball_joint")
"""Hardpoints nearest to which the default 3-2-1 support nodes are taken (mid-plane)."""


@dataclass
class InfluenceSet:
    """Unit-load stresses: coefficients (n_cases, n_nodes, 6) in Pa per N."""

    case_names: list[str]
    coefficients: np.ndarray
    node_xyz: np.ndarray | None  # (n_nodes, 3) m, None if the import has no coordinates
    node_ids: np.ndarray  # (n_nodes,) labels (FE node numbers)
    surface: np.ndarray  # (n_nodes,) bool, nodes on the surface
    meta: dict = field(default_factory=dict)

    @property
    def n_nodes(self) -> int:
        return int(self.coefficients.shape[1])

    def subset(self, mask: np.ndarray) -> InfluenceSet:
        """The same set restricted to the nodes in ``mask``."""
        return InfluenceSet(
            list(self.case_names), np.ascontiguousarray(self.coefficients[:, mask]),
            None if self.node_xyz is None else self.node_xyz[mask], self.node_ids[mask],
            self.surface[mask], dict(self.meta),
        )


# ------------------------------------------------------------------------------- built in
def cache_dir() -> Path:
    """Where FE results are cached: $SUSCOSIM_CACHE or ~/.cache/suscosim."""
    root = os.environ.get("SUSCOSIM_CACHE")
    return Path(root) if root else Path.home() / ".cache" / "suscosim"


def builtin_key(mesh_size: float, mat: Material, supports: str = "inertia_relief") -> str:
    """Hash of everything the built-in FE result depends on."""
    payload = {
        "version": CACHE_VERSION, "geometry": geo.geometry_key(), "mesh_size": mesh_size,
        "E": mat.E, "nu": mat.nu, "rho": mat.rho, "cases": BUILTIN_CASES, "supports": supports,
    }
    return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()[:16]


def unit_cases() -> list:
    """The `BUILTIN_CASES` as FE load cases (unit force 1 N or unit moment 1 N m)."""
    from .arm_fe import LoadCase

    cases = [LoadCase(f"{pt}_{ax}", geo.HARDPOINTS[pt], geo.LOAD_PATCH_RADIUS, np.eye(3)[k],
                      np.zeros(3)) for pt in FORCE_POINTS for k, ax in enumerate(AXES)]
    cases.append(LoadCase("torsion_bar_mx", np.zeros(3), geo.LOAD_PATCH_RADIUS, np.zeros(3),
                          np.array([1.0, 0.0, 0.0]),
                          points=np.array(geo.TORSION_SPRING_POINTS)))
    for k, ax in ((1, "y"), (2, "z")):
        cases.append(LoadCase(f"bump_stop_{ax}", geo.HARDPOINTS["bump_stop"],
                              geo.LOAD_PATCH_RADIUS, np.eye(3)[k], np.zeros(3)))
    return cases


def support_nodes(fe) -> list[int]:
    """Default 3-2-1 support nodes: the mid-plane nodes nearest to `SUPPORT_POINTS`."""
    return [int(np.argmin(np.linalg.norm(fe.node_xyz - geo.HARDPOINTS[p], axis=1)))
            for p in SUPPORT_POINTS]


def joint_zone_nodes(node_xyz: np.ndarray) -> np.ndarray:
    """Boolean mask of the nodes inside a joint's hub (`cosim.lower_arm.joint_zone_radius`):
    their stress is that of the idealised load introduction, so they are not assessed."""
    mask = np.zeros(node_xyz.shape[0], dtype=bool)
    for name, pt in geo.HARDPOINTS.items():
        d = np.hypot(node_xyz[:, 0] - pt[0], node_xyz[:, 1] - pt[1])
        mask |= d <= geo.joint_zone_radius(name)
    return mask


def build_fe(mesh_size: float, mat: Material):
    """The FE arm on its mesh (`arm_mesh.arm_mesh`)."""
    from .arm_fe import SolidModel
    from .arm_mesh import arm_mesh

    return SolidModel(arm_mesh(mesh_size), mat.E, mat.nu, mat.rho)


def solve_builtin(mesh_size: float, mat: Material, n_modes: int = 6,
                  supports: str = "inertia_relief") -> InfluenceSet:
    """Build and solve the FE arm: every joint load as a unit case, free arm on inertia
    relief (or ``supports = "321"``), natural frequencies and mass properties."""
    from .arm_mesh import divisions

    fe = build_fe(mesh_size, mat)
    cases = unit_cases()
    sup = support_nodes(fe)
    U, reactions = fe.solve_free(cases, sup, supports)
    coef = fe.nodal_stress(U)
    freqs = fe.natural_frequencies(n_modes) if n_modes else np.zeros(0)
    surface = fe.surface_nodes() & ~joint_zone_nodes(fe.node_xyz)
    mp = fe.mass_properties()
    meta = {
        "source": "builtin",
        "mesh_size_m": mesh_size,
        "divisions": list(divisions(mesh_size)),
        "n_elements": int(fe.mesh.nelements),
        "element": "27-node triquadratic hexahedron (scikit-fem ElementHex2)",
        "n_nodes": int(fe.n_nodes),
        "n_surface_nodes_analysed": int(surface.sum()),
        "mass_kg": float(mp["mass"]),
        "centre_of_mass_m": [float(v) for v in mp["centre_of_mass"]],
        "inertia_kg_m2": [[float(v) for v in row] for row in mp["inertia"]],
        "natural_frequencies_hz": freqs.tolist(),
        "supports": supports,
        "support_nodes": sup,
        "max_support_reaction_per_unit_load": float(np.abs(reactions).max()),
        "max_displacement_per_N_m": float(np.abs(U).max()),
    }
    return InfluenceSet([c.name for c in cases], coef, fe.node_xyz,
                        np.arange(fe.n_nodes), surface, meta)


def builtin_influence(mesh_size: float, mat: Material, use_cache: bool = True) -> InfluenceSet:
    """Built-in influence coefficients, from the disk cache when present."""
    path = cache_dir() / "fatigue" / f"influence-{builtin_key(mesh_size, mat)}.npz"
    if use_cache and path.exists():
        try:
            with np.load(path, allow_pickle=False) as z:
                return InfluenceSet(
                    json.loads(str(z["case_names"])), z["coefficients"], z["node_xyz"],
                    z["node_ids"], z["surface"], json.loads(str(z["meta"])),
                )
        except (OSError, KeyError, ValueError):
            pass  # unreadable cache: rebuild
    try:
        inf = solve_builtin(mesh_size, mat)
    except ValueError as exc:  # e.g. a mesh too coarse to put any node on a load patch
        raise ScenarioError("fatigue.mesh_size_m", mesh_size,
                            f"a finer mesh for the built-in arm ({exc})") from None
    if use_cache:
        assert inf.node_xyz is not None  # the built-in FE always has its node coordinates
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(".tmp.npz")
        np.savez(tmp, case_names=json.dumps(inf.case_names), coefficients=inf.coefficients,
                 node_xyz=inf.node_xyz, node_ids=inf.node_ids, surface=inf.surface,
                 meta=json.dumps(inf.meta))
        os.replace(tmp, path)
    return inf


# -------------------------------------------------------------------------------- imported
def _is_number(s: str) -> bool:
    try:
        float(s)
    except ValueError:
        return False
    return True


def read_case_csv(path: Path) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
    """Read one unit-load case table.

    Accepted layouts (comma separated; header lines that are not numbers are skipped, as the
    thesis stripped ANSYS headers): 6 columns ``Sx,Sy,Sz,Sxy,Syz,Szx``; 7 columns
    ``node,Sx..Szx``; 10 columns ``node,x,y,z,Sx..Szx``.

    Returns (node_ids, xyz or None, stresses (n, 6)).
    """
    p = str(path)
    rows: list[list[float]] = []
    ncol = None
    with open_user_text(path, "influence", "fatigue.mapping") as fh:
        for lineno, row in enumerate(csv.reader(fh), start=1):
            cells = [c.strip() for c in row if c.strip() != ""]
            if not cells:
                continue
            if not all(_is_number(c) for c in cells):
                if rows:
                    raise InputFileError(p, f"non-numeric value in {cells}", lineno)
                continue  # header
            if ncol is None:
                ncol = len(cells)
                if ncol not in (6, 7, 10):
                    raise InputFileError(
                        p, f"expected 6, 7 or 10 columns (Sx..Szx, node+6, node+xyz+6), "
                           f"got {ncol}", lineno)
            elif len(cells) != ncol:
                raise InputFileError(p, f"expected {ncol} columns, got {len(cells)}", lineno)
            vals = [float(c) for c in cells]
            if not np.all(np.isfinite(vals)):
                raise InputFileError(p, "non-finite value", lineno)
            rows.append(vals)
    if not rows:
        raise InputFileError(p, "no numeric rows")
    a = np.asarray(rows)
    if ncol == 6:
        return np.arange(1, a.shape[0] + 1), None, a
    if ncol == 7:
        return a[:, 0].astype(np.int64), None, a[:, 1:]
    return a[:, 0].astype(np.int64), a[:, 1:4], a[:, 4:]


def import_influence(base: Path, mapping: Mapping[str, str | Mapping[str, Any]],
                     stress_scale: float = 1.0) -> InfluenceSet:
    """Influence coefficients from per-case CSV files.

    Args:
        base: directory holding the case files (or one of them: its folder is used).
        mapping: load channel -> file name, or -> {"file": name, "scale": s}; the channel's
            load multiplies ``s`` times the file's stresses (s = -1 flips an axis).
            Channel names may be full columns (``plant/arm/ball_joint_y``) or short.
        stress_scale: multiplies every stress (e.g. 1e6 for tables in MPa per N).
    """
    base = Path(base)
    folder = base if base.is_dir() else base.parent
    names: list[str] = []
    coefs: list[np.ndarray] = []
    ids_ref = xyz_ref = None
    for channel, spec in mapping.items():
        if isinstance(spec, str):
            fname, scale = spec, 1.0
        else:
            fname, scale = spec["file"], float(spec.get("scale", 1.0))
        path = folder / fname
        ids, xyz, s = read_prnsol(path) if looks_like_prnsol(path) else read_case_csv(path)
        if ids_ref is None:
            ids_ref, xyz_ref = ids, xyz
        elif ids.shape != ids_ref.shape or not np.array_equal(ids, ids_ref):
            raise InputFileError(str(path), f"node list differs from the first case "
                                            f"({ids.size} vs {ids_ref.size} nodes)")
        names.append(short_channel(channel))
        coefs.append(s * scale * stress_scale)
    if not names:
        raise InputFileError(str(base), "no load cases in the mapping")
    assert ids_ref is not None
    return InfluenceSet(names, np.stack(coefs), xyz_ref, ids_ref,
                        np.ones(ids_ref.size, dtype=bool),
                        {"source": "imported", "folder": str(folder),
                         "mapping": {k: v for k, v in mapping.items()}})


def short_channel(name: str) -> str:
    """``plant/arm/ball_joint_z`` -> ``ball_joint_z``."""
    return name[len("plant/arm/"):] if name.startswith("plant/arm/") else name
