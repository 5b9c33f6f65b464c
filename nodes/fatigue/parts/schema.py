"""A part file (TOML): geometry, material card, joints; its keys, with an example, in
docs/parts.md, "The part file".

A load channel named at several joints is divided equally between them (the torsion bar's
moment, half at each bush eye). Every error is an `InputFileError` naming the file and key.
"""

from __future__ import annotations

import hashlib
import json
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from cosim.errors import InputFileError
from cosim.keys import NAME
from cosim.safe_open import parse_user_toml, read_user_file

from ..lib.influence_set import short_channel

COUPLINGS = ("distributing", "rigid")
UNITS = {"m": 1.0, "mm": 1e-3}
AXES = ("x", "y", "z")
BUILTIN_PREFIX = "builtin:"


@dataclass(frozen=True)
class PartMaterial:
    """Elastic card: E [Pa], ν [-], ρ [kg/m³], yield S_y [Pa] (for the 3 g check)."""

    name: str
    E: float
    nu: float
    rho: float
    Sy: float


@dataclass
class Joint:
    """A joint: its node selection, coupling, hardware mass and unit load channels."""

    name: str
    centre: np.ndarray
    radius: float | None
    axis: np.ndarray | None
    length: float | None
    node_set: str | None
    coupling: str
    mass_kg: float
    zone: float
    forces: dict[str, str] = field(default_factory=dict)   # axis -> channel
    moments: dict[str, str] = field(default_factory=dict)  # axis -> channel


@dataclass
class Part:
    """A validated part file."""

    path: Path
    name: str
    geometry: str  # absolute path, or "builtin:lower_arm"
    kind: str  # "cad", "mesh" or "builtin"
    scale: float
    material: PartMaterial
    joints: list[Joint]
    mesh_size: float
    fillet_size: float
    convergence: list[float]
    digest: str
    convergence_local: list[float] = field(default_factory=list)
    convergence_radius: float = 0.02
    refine: list[tuple[float, float, float, float, float]] = field(default_factory=list)
    """The mesh recipe's local refinement: balls (x, y, z [m], radius [m], size [m])."""

    @property
    def channels(self) -> list[str]:
        """Load channels in first-appearance order."""
        out: list[str] = []
        for j in self.joints:
            for ch in list(j.forces.values()) + list(j.moments.values()):
                if ch not in out:
                    out.append(ch)
        return out


def material_card(name: str) -> PartMaterial:
    """A material card by name (817M40: Table 6.2 via nodes.fatigue.lib.material)."""
    if name.upper() in ("817M40", "EN24T"):
        from ..materials import steel_817M40

        m = steel_817M40()
        return PartMaterial("817M40", m.E, m.nu, m.rho, m.Sy)
    raise KeyError(name)


def _num(src: str, key: str, v: Any, lo: float = 0.0, hi: float = math.inf) -> float:
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v) \
            or not lo < v <= hi:
        raise InputFileError(src, f"key {key}: got {v!r}, expected a number in ({lo}, {hi}]")
    return float(v)


def _vec(src: str, key: str, v: Any) -> np.ndarray:
    if not isinstance(v, list) or len(v) != 3 or not all(
            isinstance(c, int | float) and not isinstance(c, bool) for c in v):
        raise InputFileError(src, f"key {key}: got {v!r}, expected [x, y, z] numbers")
    return np.asarray(v, dtype=float)


def _check_keys(src: str, where: str, table: dict, allowed: tuple[str, ...]) -> None:
    for k in table:
        if k not in allowed:
            raise InputFileError(src, f"unknown key {where}{k} (accepted: {', '.join(allowed)})")


def _joint(src: str, i: int, raw: Any, scale_hp: float) -> Joint:
    where = f"joint[{i}]."
    if not isinstance(raw, dict):
        raise InputFileError(src, f"[[joint]] {i} is not a table")
    _check_keys(src, where, raw, ("name", "centre", "radius", "axis", "length", "node_set",
                                  "coupling", "mass_kg", "zone", "forces", "moments"))
    name = raw.get("name")
    if not isinstance(name, str) or not name:
        raise InputFileError(src, f"key {where}name: expected a non-empty string")
    where = f"joint '{name}'."
    c = raw.get("centre")
    if isinstance(c, str) and c.startswith("hardpoint:"):
        from .hardpoints import hardpoints  # the lower and upper arms' (one definition)

        hp, known = c[len("hardpoint:"):], hardpoints()
        if hp not in known:
            raise InputFileError(src, f"key {where}centre: unknown hardpoint {hp!r} (known: "
                                      f"{', '.join(known)})")
        centre = known[hp]
    elif c is None:
        raise InputFileError(src, f"key {where}centre: missing (a point [m] or "
                                  f"\"hardpoint:NAME\")")
    else:
        centre = _vec(src, where + "centre", c) * scale_hp
    node_set = raw.get("node_set")
    if node_set is not None and not isinstance(node_set, str):
        raise InputFileError(src, f"key {where}node_set: expected a string")
    radius = raw.get("radius")
    if radius is None and node_set is None:
        raise InputFileError(src, f"key {where}radius: give radius (or node_set)")
    radius = None if radius is None else _num(src, where + "radius", radius, 0.0, 10.0)
    axis = raw.get("axis")
    if axis is not None:
        axis = _vec(src, where + "axis", axis)
        if np.linalg.norm(axis) == 0:
            raise InputFileError(src, f"key {where}axis: zero vector")
        axis = axis / np.linalg.norm(axis)
    length = raw.get("length")
    length = None if length is None else _num(src, where + "length", length, 0.0, 10.0)
    coupling = raw.get("coupling", "distributing")
    if coupling not in COUPLINGS:
        raise InputFileError(src, f"key {where}coupling: got {coupling!r}, expected one of "
                                  f"{', '.join(COUPLINGS)}")
    mass = raw.get("mass_kg", 0.0)
    mass = 0.0 if mass == 0 else _num(src, where + "mass_kg", mass, 0.0, 1e4)
    zone = _num(src, where + "zone", raw.get("zone", 0.010), 0.0, 10.0)
    loads: dict[str, dict[str, str]] = {}
    for kind in ("forces", "moments"):
        t = raw.get(kind, {})
        if not isinstance(t, dict):
            raise InputFileError(src, f"key {where}{kind}: expected a table {{x = \"channel\"}}")
        for ax, ch in t.items():
            if ax not in AXES or not isinstance(ch, str) or not ch:
                raise InputFileError(src, f"key {where}{kind}.{ax}: expected x/y/z = "
                                          f"\"channel name\", got {ax} = {ch!r}")
        loads[kind] = {ax: short_channel(ch) for ax, ch in t.items()}
    return Joint(name, centre, radius, axis, length, node_set, coupling, mass, zone,
                 loads["forces"], loads["moments"])


def _refine(src: str, m: dict, scale: float) -> list[tuple[float, float, float, float, float]]:
    """``mesh.refine_centres`` ([x, y, z] in the part's length unit) with ``refine_radius`` and
    ``refine_size`` [m]: the recipe's refinement balls; both or neither."""
    centres = m.get("refine_centres")
    given = [k for k in ("refine_radius", "refine_size") if k in m]
    if centres is None:
        if given:
            raise InputFileError(src, f"key mesh.{given[0]}: given without "
                                      f"mesh.refine_centres")
        return []
    if not isinstance(centres, list) or not centres:
        raise InputFileError(src, "key mesh.refine_centres: expected a list of [x, y, z] "
                                  "points (the part's length unit)")
    for k in ("refine_radius", "refine_size"):
        if k not in m:
            raise InputFileError(src, f"key mesh.{k}: missing (mesh.refine_centres needs "
                                      f"refine_radius and refine_size, in m)")
    r = _num(src, "mesh.refine_radius", m["refine_radius"], 1e-5, 1.0)
    h = _num(src, "mesh.refine_size", m["refine_size"], 1e-5, 1.0)
    out = []
    for i, c in enumerate(centres):
        x, y, z = (float(v) for v in _vec(src, f"mesh.refine_centres[{i}]", c) * scale)
        out.append((x, y, z, r, h))
    return out


def _content(raw: dict) -> bytes:
    """A TOML file's parsed content as canonical JSON: the part key's input, so that a
    comment or a reflowed line does not orphan a part's shipped results."""
    return json.dumps(raw, sort_keys=True, default=str).encode()


def load_part(path: str | Path) -> Part:
    """Read and validate a part file; an `InputFileError` names the file and the key."""
    path = Path(path).resolve()
    src = str(path)
    try:
        raw_bytes = read_user_file(path, "scenario", "part file")
        text = raw_bytes.decode()
    except (OSError, UnicodeDecodeError) as exc:
        raise InputFileError(src, f"not a readable TOML file: {exc}") from None
    raw = parse_user_toml(text, src, "part file")
    _check_keys(src, "", raw, ("part", "mesh", "joint"))
    p = raw.get("part")
    if not isinstance(p, dict):
        raise InputFileError(src, "missing table [part]")
    _check_keys(src, "part.", p, ("name", "geometry", "length_unit", "material"))
    name = p.get("name", path.stem)
    if not isinstance(name, str) or not NAME.match(name):  # it names cache and result files
        raise InputFileError(src, f"key part.name: got {name!r:.80}, expected 1-64 letters, "
                                  "digits, '_', '.', '-', not starting with '.' or '-'")
    geometry = p.get("geometry")
    if not isinstance(geometry, str) or not geometry:
        raise InputFileError(src, "key part.geometry: expected a STEP or mesh file name, or "
                                  "\"builtin:lower_arm\"")
    unit = p.get("length_unit", "m")
    if unit not in UNITS:
        raise InputFileError(src, f"key part.length_unit: got {unit!r}, expected m or mm")
    digest_parts = [_content(raw)]  # what the file says, not its comments or layout
    if geometry.startswith(BUILTIN_PREFIX):
        if geometry != "builtin:lower_arm":
            raise InputFileError(src, f"key part.geometry: unknown built-in {geometry!r} "
                                      f"(known: builtin:lower_arm)")
        from .cad_arm import DEFAULT_PARAMS

        kind, geo_path = "builtin", geometry
        digest_parts.append(_content(tomllib.loads(DEFAULT_PARAMS.read_text())))
    else:
        gp = (path.parent / geometry).resolve()
        suffix = gp.suffix.lower()
        from .mesh import CAD_SUFFIXES, MESH_SUFFIXES

        if suffix in CAD_SUFFIXES:
            kind = "cad"
        elif suffix in MESH_SUFFIXES:
            kind = "mesh"
        else:
            raise InputFileError(src, f"key part.geometry: {geometry!r} is neither STEP "
                                      f"({', '.join(CAD_SUFFIXES)}) nor a mesh "
                                      f"({', '.join(MESH_SUFFIXES)})")
        if not gp.is_file():
            raise InputFileError(src, f"key part.geometry: file not found: {gp}")
        geo_path = str(gp)
        digest_parts.append(gp.read_bytes())
    mat_raw = p.get("material", "817M40")
    if isinstance(mat_raw, str):
        try:
            material = material_card(mat_raw)
        except KeyError:
            raise InputFileError(src, f"key part.material: unknown card {mat_raw!r} (known: "
                                      f"817M40; or an inline table E, nu, rho, Sy)") from None
    elif isinstance(mat_raw, dict):
        _check_keys(src, "part.material.", mat_raw, ("name", "E", "nu", "rho", "Sy"))
        for k in ("E", "nu", "rho", "Sy"):
            if k not in mat_raw:
                raise InputFileError(src, f"key part.material.{k}: missing")
        material = PartMaterial(str(mat_raw.get("name", "inline")),
                                _num(src, "part.material.E", mat_raw["E"]),
                                _num(src, "part.material.nu", mat_raw["nu"], 0.0, 0.4999),
                                _num(src, "part.material.rho", mat_raw["rho"]),
                                _num(src, "part.material.Sy", mat_raw["Sy"]))
    else:
        raise InputFileError(src, "key part.material: expected a card name or a table")
    m = raw.get("mesh", {})
    if not isinstance(m, dict):
        raise InputFileError(src, "key mesh: expected a table")
    _check_keys(src, "mesh.", m, ("size", "fillet_size", "convergence", "convergence_local",
                                  "convergence_radius", "refine_centres", "refine_radius",
                                  "refine_size"))
    size = _num(src, "mesh.size", m.get("size", 0.012), 1e-4, 1.0)
    fsize = _num(src, "mesh.fillet_size", m.get("fillet_size", size / 3), 1e-5, 1.0)
    conv = m.get("convergence", [size])
    if not isinstance(conv, list) or not conv:
        raise InputFileError(src, "key mesh.convergence: expected a list of element sizes [m]")
    conv = [_num(src, "mesh.convergence", v, 1e-4, 1.0) for v in conv]
    conv_local = m.get("convergence_local", [])
    if not isinstance(conv_local, list):
        raise InputFileError(src, "key mesh.convergence_local: expected a list of element "
                                  "sizes [m]")
    conv_local = [_num(src, "mesh.convergence_local", v, 1e-5, 1.0) for v in conv_local]
    conv_radius = _num(src, "mesh.convergence_radius", m.get("convergence_radius", 0.02),
                       1e-4, 1.0)
    refine = _refine(src, m, UNITS[unit])
    if refine and kind == "mesh":
        raise InputFileError(src, "key mesh.refine_centres: local refinement needs a CAD "
                                  "geometry (a mesh file is taken as it is)")
    joints_raw = raw.get("joint", [])
    if not isinstance(joints_raw, list) or not joints_raw:
        raise InputFileError(src, "missing [[joint]] tables (at least one joint)")
    joints = [_joint(src, i, j, UNITS[unit]) for i, j in enumerate(joints_raw)]
    names = [j.name for j in joints]
    dup = {n for n in names if names.count(n) > 1}
    if dup:
        raise InputFileError(src, f"joint names repeated: {sorted(dup)}")
    for j in joints:
        if not j.forces and not j.moments:
            raise InputFileError(src, f"key joint '{j.name}': no forces or moments (a joint "
                                      f"carries at least one load channel)")
        if j.coupling == "rigid":
            raise InputFileError(src, f"key joint '{j.name}'.coupling: \"rigid\" is not "
                                      f"implemented yet; use \"distributing\"")
    h = hashlib.sha256()
    for b in digest_parts:
        h.update(hashlib.sha256(b).digest())
    return Part(path, str(name), geo_path, kind, UNITS[unit], material, joints, size, fsize,
                conv, h.hexdigest()[:16], conv_local, conv_radius, refine)
