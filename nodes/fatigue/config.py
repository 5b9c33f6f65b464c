"""Fatigue worker configuration: the ``[fatigue]`` section of a scenario, validated.

Keys (all optional; SI units):

=====================  ===================  =================================================
key                    default              meaning
=====================  ===================  =================================================
influence              "builtin"            "builtin" (FE arm) or path to the imported CSV
                                            folder (relative to the scenario's folder)
mapping                {}                   imported only: channel -> file or
                                            {file = "...", scale = -1.0}
stress_scale           1.0                  imported only: multiplies table stresses (1e6 if MPa)
equivalent             "abs_max_principal"  or "signed_von_mises"
method                 "stress_life"        or "strain_life" (Coffin-Manson-Basquin + Neuber)
mean_stress            "goodman"            "none", "goodman", "gerber", "morrow", "swt"
residue                "repeated"           "repeated" (track driven again and again) or
                                            "half_cycles" (ASTM E1049)
endurance_limit        false                no damage below Se (stress amplitude, Pa)
material               {}                   overrides: E, nu, rho, Su, Sy, sf', b, ef', c,
                                            K', n', Se (Pa; primes optional)
mesh_size_m            0.02                 built-in FE element size (m)
nodes                  "surface"            "surface" or "all" nodes analysed
track_length_m         none                 length of one pass (m); else from the road/run
repeats_basis_m        none                 also give life in repeats of this length (m)
block_samples          500                  live: samples per update block
live                   "auto"               run the fatigue node during the run (true /
                                            false; "auto": when the plant reports arm loads)
=====================  ===================  =================================================
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path

from cosim.errors import ScenarioError

from .damage import METHODS
from .equivalent_stress import EQUIVALENTS
from .material import ALIASES, Material, steel_817M40, with_overrides
from .mean_stress import MEAN_STRESS_METHODS

NODE_SETS = ("surface", "all")
RESIDUES = ("repeated", "half_cycles")


@dataclass(frozen=True)
class FatigueConfig:
    """Validated fatigue settings (see module docstring for keys and defaults)."""

    influence: str = "builtin"
    mapping: tuple[tuple[str, str, float], ...] = ()
    stress_scale: float = 1.0
    equivalent: str = "abs_max_principal"
    method: str = "stress_life"
    mean_stress: str = "goodman"
    residue: str = "repeated"
    endurance_limit: bool = False
    material_overrides: tuple[tuple[str, float], ...] = ()
    mesh_size_m: float = 0.02
    nodes: str = "surface"
    track_length_m: float | None = None
    repeats_basis_m: float | None = None
    block_samples: int = 500
    live: bool | str = "auto"
    base_dir: str = field(default=".", compare=False)

    @property
    def material(self) -> Material:
        return with_overrides(steel_817M40(), dict(self.material_overrides))

    @property
    def influence_path(self) -> Path:
        p = Path(self.influence).expanduser()
        return p if p.is_absolute() else Path(self.base_dir) / p

    def as_dict(self) -> dict:
        d = asdict(self)
        d["mapping"] = {c: {"file": f, "scale": s} for c, f, s in self.mapping}
        d["material"] = dict(self.material_overrides)
        del d["material_overrides"], d["base_dir"]
        return d

    @classmethod
    def from_dict(cls, d: Mapping | None, key_prefix: str = "fatigue",
                  base_dir: str | Path = ".") -> FatigueConfig:
        """Validate a scenario section; a bad key or value raises ScenarioError(dotted key)."""
        d = dict(d or {})

        def key(k: str) -> str:
            return f"{key_prefix}.{k}" if key_prefix else k

        def choice(k: str, options: tuple[str, ...], default: str) -> str:
            v = d.pop(k, default)
            if v not in options:
                raise ScenarioError(key(k), v, "one of " + ", ".join(repr(o) for o in options))
            return v

        def number(k: str, default, *, positive: bool = True, optional: bool = False):
            v = d.pop(k, default)
            if v is None and optional:
                return None
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ScenarioError(key(k), v, "a finite number" + (" > 0" if positive else ""))
            if positive and v <= 0:
                raise ScenarioError(key(k), v, "a number > 0")
            return float(v)

        influence = d.pop("influence", "builtin")
        if not isinstance(influence, str) or not influence:
            raise ScenarioError(key("influence"), influence, '"builtin" or a path to CSV files')
        raw_map = d.pop("mapping", {})
        if not isinstance(raw_map, Mapping):
            raise ScenarioError(key("mapping"), raw_map, "a table channel -> case file")
        mapping: list[tuple[str, str, float]] = []
        for ch, spec in raw_map.items():
            k = key(f"mapping.{ch}")
            if isinstance(spec, str):
                mapping.append((str(ch), spec, 1.0))
            elif isinstance(spec, Mapping) and isinstance(spec.get("file"), str):
                extra = set(spec) - {"file", "scale"}
                sc = spec.get("scale", 1.0)
                if extra or isinstance(sc, bool) or not isinstance(sc, (int, float)):
                    raise ScenarioError(k, dict(spec), '{file = "<csv>", scale = <number>}')
                mapping.append((str(ch), spec["file"], float(sc)))
            else:
                raise ScenarioError(k, spec, 'a file name or {file = "<csv>", scale = <number>}')
        if influence != "builtin" and not mapping:
            raise ScenarioError(key("mapping"), raw_map,
                                "a mapping of load channels to case files for imported tables")
        raw_mat = d.pop("material", {})
        if not isinstance(raw_mat, Mapping):
            raise ScenarioError(key("material"), raw_mat, "a table of material overrides")
        mat: list[tuple[str, float]] = []
        for mk, mv in raw_mat.items():
            if mk not in ALIASES:
                raise ScenarioError(key(f"material.{mk}"), mv,
                                    "a key among " + ", ".join(sorted(ALIASES)))
            if isinstance(mv, bool) or not isinstance(mv, (int, float)) or not math.isfinite(mv):
                raise ScenarioError(key(f"material.{mk}"), mv, "a finite number (SI units)")
            name = ALIASES[mk]
            if name in ("b", "c") and mv >= 0:
                raise ScenarioError(key(f"material.{mk}"), mv, "a negative exponent")
            if name not in ("b", "c") and mv <= 0:
                raise ScenarioError(key(f"material.{mk}"), mv, "a number > 0")
            if name == "nu" and not mv < 0.5:
                raise ScenarioError(key(f"material.{mk}"), mv, "a Poisson's ratio < 0.5")
            mat.append((name, float(mv)))
        endurance = d.pop("endurance_limit", False)
        if not isinstance(endurance, bool):
            raise ScenarioError(key("endurance_limit"), endurance, "true or false")
        live = d.pop("live", "auto")
        if live not in (True, False, "auto"):
            raise ScenarioError(key("live"), live, 'true, false or "auto"')
        block = d.pop("block_samples", 500)
        if isinstance(block, bool) or not isinstance(block, int) or block < 1:
            raise ScenarioError(key("block_samples"), block, "an integer >= 1")
        cfg = cls(
            influence=influence,
            mapping=tuple(mapping),
            stress_scale=number("stress_scale", 1.0),
            equivalent=choice("equivalent", EQUIVALENTS, "abs_max_principal"),
            method=choice("method", METHODS, "stress_life"),
            mean_stress=choice("mean_stress", MEAN_STRESS_METHODS, "goodman"),
            residue=choice("residue", RESIDUES, "repeated"),
            endurance_limit=endurance,
            material_overrides=tuple(mat),
            mesh_size_m=number("mesh_size_m", 0.02),
            nodes=choice("nodes", NODE_SETS, "surface"),
            track_length_m=number("track_length_m", None, optional=True),
            repeats_basis_m=number("repeats_basis_m", None, optional=True),
            block_samples=block,
            live=live,
            base_dir=str(base_dir),
        )
        if not 0.002 <= cfg.mesh_size_m <= 0.1:
            raise ScenarioError(key("mesh_size_m"), cfg.mesh_size_m, "between 0.002 and 0.1 m")
        if d:
            k = sorted(d)[0]
            raise ScenarioError(key(k), d[k], "no such key (known: influence, mapping, "
                                "stress_scale, equivalent, method, mean_stress, residue, "
                                "endurance_limit, material, mesh_size_m, nodes, track_length_m, "
                                "repeats_basis_m, block_samples, live)")
        return cfg
