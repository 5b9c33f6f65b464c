"""A part's FE model and its influence coefficients (the form the fatigue worker consumes).

:func:`part_model` meshes the part (gmsh or meshio), builds the P2-tet FE, selects each
joint's nodes, adds its hardware mass; :func:`solve_part` solves every load channel as a unit
case on inertia relief and returns the `InfluenceSet` of **the assessed surface nodes only**
(the fatigue node evaluates every one of them every step) with the part's mass, modes and
mesh in ``meta``; :func:`part_influence` caches that on disk (``$SUSCOSIM_CACHE/parts``,
key: the part file's and geometry's bytes, the mesh sizes, the code version) in the form of
the shipped results (:func:`save_npz`, :func:`from_npz`; :mod:`.results_file`).

Assessment rule (printed by ``suscosim part check``): a surface node is assessed unless it
lies within its joint's ``zone`` [m] of any node of that joint's coupling: there the stress is
that of the idealised load introduction (a distributing coupling on a bore), not of the
pressed-in bush sleeve or ball-joint cartridge, which are assessed with their own models.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from cosim.errors import InputFileError

from ..influence import cache_dir
from ..lib.influence_set import InfluenceSet
from ..lib.solid import PartFE, TetMesh
from .mesh import Ball, mesh_cad, read_mesh
from .schema import Joint, Part

VERSION = "part-fe-v1"
AXIS_INDEX = {"x": 0, "y": 1, "z": 2}


@dataclass
class PartModel:
    """The meshed part: FE, joint node sets (P2 node indices), assessed-node mask."""

    part: Part
    mesh: TetMesh
    fe: PartFE
    joint_nodes: dict[str, np.ndarray]
    surface: np.ndarray
    assessed: np.ndarray
    mesh_size: float
    fillet_size: float


def select_joint_nodes(fe: PartFE, joint: Joint, mesh: TetMesh, surface: np.ndarray,
                       src: str) -> np.ndarray:
    """Surface nodes of a joint: a named node set (its vertices), or the surface nodes within
    ``radius`` of the centre (of the axis through it, within ``length``/2 along it)."""
    if joint.node_set is not None:
        if joint.node_set not in mesh.node_sets:
            raise InputFileError(src, f"key joint '{joint.name}'.node_set: {joint.node_set!r} "
                                      f"not in the mesh (sets: {sorted(mesh.node_sets)})")
        idx = np.asarray(mesh.node_sets[joint.node_set], dtype=np.int64)
    else:
        r = fe.node_xyz - joint.centre
        if joint.axis is not None:
            along = r @ joint.axis
            d = np.linalg.norm(r - along[:, None] * joint.axis, axis=1)
            ok = d <= joint.radius
            if joint.length is not None:
                ok &= np.abs(along) <= 0.5 * joint.length
        else:
            ok = np.linalg.norm(r, axis=1) <= joint.radius
        idx = np.nonzero(ok & surface)[0]
    if idx.size < 3:
        raise InputFileError(src, f"joint '{joint.name}': {idx.size} surface nodes selected "
                                  f"(need >= 3): check its centre, radius, axis, length")
    return idx


def support_nodes(xyz: np.ndarray) -> list[int]:
    """Three far-apart nodes for the 3-2-1 support (their reactions are zero to rounding on
    inertia relief, so the choice does not change the stresses)."""
    c = xyz.mean(axis=0)
    a = int(np.argmax(np.linalg.norm(xyz - c, axis=1)))
    b = int(np.argmax(np.linalg.norm(xyz - xyz[a], axis=1)))
    area = np.linalg.norm(np.cross(xyz - xyz[a], xyz[b] - xyz[a]), axis=1)
    return [a, b, int(np.argmax(area))]


def part_model(part: Part, mesh_size: float | None = None,
               fillet_size: float | None = None, refine: Sequence[Ball] | None = None
               ) -> PartModel:
    """Mesh and set up the FE of a part (sizes default to the part file's); ``refine``:
    local refinement balls of the gmsh mesh (``mesh.mesh_cad``; CAD parts only), by default
    the part file's recipe (``mesh.refine_centres``; ``()``: none)."""
    size = part.mesh_size if mesh_size is None else float(mesh_size)
    refine = part.refine if refine is None else refine
    fsize = (part.fillet_size * size / part.mesh_size if fillet_size is None
             else float(fillet_size))
    src = str(part.path)
    if part.kind == "builtin":
        from .cad_arm import load_params

        mesh = mesh_cad(None, size, fsize, builtin_params=load_params(), refine=refine)
    elif part.kind == "cad":
        mesh = mesh_cad(Path(part.geometry), size, fsize, refine=refine)  # STEP: its unit
    else:
        if refine:
            raise ValueError("local refinement needs a CAD part (a mesh file is read as is)")
        mesh = read_mesh(Path(part.geometry), scale=part.scale)
    mat = part.material
    fe = PartFE(mesh, mat.E, mat.nu, mat.rho)
    surface = fe.surface_nodes()
    joint_nodes = {j.name: select_joint_nodes(fe, j, mesh, surface, src) for j in part.joints}
    for j in part.joints:
        if j.mass_kg > 0.0:
            fe.add_point_mass(joint_nodes[j.name], j.mass_kg)
    from scipy.spatial import cKDTree  # here: every run's preflight imports this module

    zone = np.zeros(fe.n_nodes, dtype=bool)
    for j in part.joints:
        d, _ = cKDTree(fe.node_xyz[joint_nodes[j.name]]).query(fe.node_xyz)
        zone |= d <= j.zone
    return PartModel(part, mesh, fe, joint_nodes, surface, surface & ~zone, size, fsize)


def load_vectors(pm: PartModel) -> tuple[list[str], np.ndarray]:
    """Every load channel as a unit case: (channel names, B (n_dofs, n_cases))."""
    names = pm.part.channels
    B = np.zeros((pm.fe.K_size, len(names)))
    for k, ch in enumerate(names):
        acts = [(j, ax, kind) for j in pm.part.joints
                for kind, table in (("force", j.forces), ("moment", j.moments))
                for ax, c in table.items() if c == ch]
        for j, ax, kind in acts:
            e = np.eye(3)[AXIS_INDEX[ax]] / len(acts)
            f, m = (e, np.zeros(3)) if kind == "force" else (np.zeros(3), e)
            B[:, k] += pm.fe.coupling_load(pm.joint_nodes[j.name], j.centre, f, m)
    return names, B


def solve_part(pm: PartModel, n_modes: int = 6) -> tuple[InfluenceSet, dict[str, Any]]:
    """Unit cases on inertia relief and the modes. Returns the influence set of the
    assessed surface nodes, and the full-field extras (all-node stresses, mode shapes) for
    the model card."""
    fe = pm.fe
    names, B = load_vectors(pm)
    sup = support_nodes(fe.node_xyz)
    U, reactions = fe.solve_loads(B, sup)
    coef = fe.nodal_stress(U)
    freqs, shapes = fe.modes(n_modes) if n_modes else (np.zeros(0), None)
    mp = fe.mass_properties()
    nv = pm.mesh.p.shape[0]
    labels = np.r_[pm.mesh.labels, pm.mesh.labels.max() + 1 + np.arange(fe.n_nodes - nv)]
    a = pm.assessed
    meta = {
        "source": "part", **part_names(pm.part), "part_name": pm.part.name,
        "mesh_size_m": pm.mesh_size,
        "fillet_size_m": pm.fillet_size, "n_elements": int(pm.mesh.t.shape[0]),
        "element": "10-node quadratic tetrahedron (scikit-fem ElementTetP2)",
        "n_nodes": int(fe.n_nodes), "n_surface_nodes_analysed": int(a.sum()),
        "mass_kg": float(mp["mass"]), "solid_mass_kg": float(mp["solid_mass"]),
        "hardware_mass_kg": float(mp["hardware_mass"]),
        "centre_of_mass_m": [float(v) for v in np.asarray(mp["centre_of_mass"])],
        "inertia_kg_m2": [[float(v) for v in row] for row in np.asarray(mp["inertia"])],
        "natural_frequencies_hz": [float(f) for f in freqs],
        "supports": "inertia_relief", "support_nodes": sup,
        "max_support_reaction_per_unit_load": float(np.abs(reactions).max()),
        "joints": {j.name: {"nodes": int(pm.joint_nodes[j.name].size), "zone_m": j.zone,
                            "coupling": j.coupling, "mass_kg": j.mass_kg}
                   for j in pm.part.joints},
    }
    inf = InfluenceSet(names, np.ascontiguousarray(coef[:, a]), fe.node_xyz[a], labels[a],
                       np.ones(int(a.sum()), dtype=bool), meta)
    return inf, {"coef": coef, "U": U, "B": B, "shapes": shapes, "labels": labels}


def part_names(part: Part) -> dict[str, str]:
    """How results name their part, portable (no folder of the machine that solved it):
    ``part`` the part file's name, ``part_sha256`` the SHA-256 of its bytes (to recognise
    it), ``geometry`` its STEP or mesh file relative to the part file's folder (or
    ``"builtin:lower_arm"``)."""
    geo = part.geometry if part.kind == "builtin" else \
        Path(os.path.relpath(part.geometry, part.path.parent)).as_posix()
    return {"part": part.path.name,
            "part_sha256": hashlib.sha256(part.path.read_bytes()).hexdigest(),
            "geometry": geo}


def part_key(part: Part, mesh_size: float, fillet_size: float) -> str:
    payload = {"version": VERSION, "digest": part.digest, "size": mesh_size,
               "fillet": fillet_size}
    return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()[:16]


def part_influence(part: Part, mesh_size: float | None = None, use_cache: bool = True
                   ) -> InfluenceSet:
    """The part's influence coefficients (assessed surface nodes), from the disk cache
    when present."""
    size = part.mesh_size if mesh_size is None else float(mesh_size)
    fsize = part.fillet_size * size / part.mesh_size
    path = cache_dir() / "parts" / f"{part.name}-{part_key(part, size, fsize)}.npz"
    if use_cache and path.exists():
        try:
            with np.load(path, allow_pickle=False) as z:
                return from_npz(z)
        except (OSError, KeyError, ValueError):
            pass  # unreadable cache: rebuild
    inf, _ = solve_part(part_model(part, size, fsize))
    if use_cache:
        path.parent.mkdir(parents=True, exist_ok=True)
        save_npz(path, inf)
    return inf


def save_npz(path: Path, inf: InfluenceSet, meta: dict | None = None, compressed: bool = False,
             **head: Any) -> None:
    """Write ``inf`` (its ``meta`` replaced by ``meta`` when given) and the ``head`` entries as
    an ``.npz`` (no pickles; names and meta as JSON), aside then renamed into place."""
    assert inf.node_xyz is not None, "a part's FE always has its node coordinates"
    tmp = path.with_name(path.name + f".{os.getpid()}.tmp")
    with open(tmp, "wb") as fh:
        (np.savez_compressed if compressed else np.savez)(
            fh, **head, case_names=json.dumps(inf.case_names), coefficients=inf.coefficients,
            node_xyz=inf.node_xyz, node_ids=inf.node_ids, surface=inf.surface,
            meta=json.dumps(inf.meta if meta is None else meta))
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, path)


def from_npz(z: Any) -> InfluenceSet:
    """The influence set of an open ``.npz`` written by :func:`save_npz`."""
    return InfluenceSet(json.loads(str(z["case_names"])), z["coefficients"], z["node_xyz"],
                        z["node_ids"], z["surface"], json.loads(str(z["meta"])))
