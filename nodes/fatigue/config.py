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
endurance              "haibach"            below the S-N curve's Se: "haibach" (modified
                                            Miner, slope 2k-1), "elementary" (no damage) or
                                            "none"; tested on the mean-corrected amplitude
endurance_limit        (old key)            true = "elementary", false = "none"
material               {}                   overrides: E, nu, rho, Su, Sy, sf', b, ef', c,
                                            K', n', Se (Pa; primes optional); and
                                            cyclic = "uml" | "table_6_2" | "compatible"
component              {}                   the arm's S-N curve (Marin factors), below
mesh_size_m            0.02                 built-in FE element size (m)
nodes                  "surface"            "surface" or "all" nodes analysed
track_length_m         none                 length of one pass (m); else from the road/run
repeats_basis_m        none                 also give life in repeats of this length (m)
block_samples          500                  live: samples per update block
live                   "auto"               run the fatigue node during the run (true /
                                            false; "auto": when the plant reports arm loads)
=====================  ===================  =================================================

``[fatigue.component]`` (Shigley's Marin factors, `material.ComponentSpec`; SI units):

=====================  ===================  =================================================
key                    default              meaning
=====================  ===================  =================================================
enabled                true                 false: the material's polished-specimen Basquin
                                            line (σ'f, b, knee at Se = material Se)
surface                "forged"             "forged", "hot_rolled", "machined", "cold_drawn",
                                            "ground", "polished" (ka = a Sut^b)
section_h_m            0.042                depth h of the critical section (m) ...
section_b_m            0.022                ... and width b: d_e = 0.808 sqrt(h b) for kb
equivalent_diameter_m  none                 d_e (m) given directly (then h, b are not used)
loading                "bending"            or "axial" (kc = 0.85, kb = 1)
reliability            0.5                  R of the curve: ke = 1 - 0.08 z_a (0.5 -> 1)
temperature_c          20.0                 operating temperature (°C) for kd
kf                     1.0                  miscellaneous-effects factor (peening, ...)
knee_cycles            1e6                  cycles Ne at the knee (Se)
=====================  ===================  =================================================
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

from cosim.errors import ScenarioError

from .damage import METHODS
from .equivalent_stress import EQUIVALENTS
from .life_models import ENDURANCE_MODES
from .material import (
    ALIASES,
    CYCLIC_CURVES,
    LOADINGS,
    SURFACE_FACTORS,
    ComponentSpec,
    Material,
    compatibility,
    component_sn_curve,
    material_sn_curve,
    steel_817M40,
    with_overrides,
)
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
    endurance: str = "haibach"
    material_overrides: tuple[tuple[str, float], ...] = ()
    cyclic: str = "uml"
    component: ComponentSpec | None = field(default_factory=ComponentSpec)
    mesh_size_m: float = 0.02
    nodes: str = "surface"
    track_length_m: float | None = None
    repeats_basis_m: float | None = None
    block_samples: int = 500
    live: bool | str = "auto"
    base_dir: str = field(default=".", compare=False)

    @property
    def endurance_limit(self) -> str:
        """The endurance treatment (what `damage.miner_per_node` takes as endurance_limit)."""
        return self.endurance

    @property
    def material(self) -> Material:
        """817M40 with the overrides, its S-N curve (component or material) attached."""
        mat = with_overrides(steel_817M40(self.cyclic), dict(self.material_overrides))
        if self.component is None:
            sn = material_sn_curve(mat, self.endurance)
        else:
            sn = component_sn_curve(mat, self.component, self.endurance)
        return replace(mat, sn=sn)

    def fatigue_properties(self) -> dict:
        """What the summary reports: the material constants with their sources, K'/n'
        compatibility, and the S-N curve with every factor (stresses in Pa)."""
        mat = self.material
        return {"material": mat.as_dict(), "material_source": dict(mat.source),
                "cyclic_compatibility": compatibility(mat),
                "sn_curve": mat.sn.as_dict() if mat.sn is not None else None}

    @property
    def influence_path(self) -> Path:
        p = Path(self.influence).expanduser()
        return p if p.is_absolute() else Path(self.base_dir) / p

    def as_dict(self) -> dict:
        d = asdict(self)
        d["mapping"] = {c: {"file": f, "scale": s} for c, f, s in self.mapping}
        d["material"] = dict(self.material_overrides)
        d["material"]["cyclic"] = self.cyclic
        if self.component is None:
            d["component"] = {"enabled": False}
        else:
            comp = asdict(self.component)
            comp["equivalent_diameter_m"] = comp.pop("d_e_m")
            d["component"] = {"enabled": True, **comp}
        d["fatigue_properties"] = self.fatigue_properties()
        del d["material_overrides"], d["base_dir"], d["cyclic"]
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
        raw_mat = dict(raw_mat)
        cyclic = raw_mat.pop("cyclic", "uml")
        if cyclic not in CYCLIC_CURVES:
            raise ScenarioError(key("material.cyclic"), cyclic,
                                "one of " + ", ".join(repr(o) for o in CYCLIC_CURVES))
        for mk, mv in raw_mat.items():
            if mk not in ALIASES:
                raise ScenarioError(key(f"material.{mk}"), mv,
                                    "a key among " + ", ".join(sorted(ALIASES)) + ", cyclic")
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
        endurance = d.pop("endurance", None)
        if endurance is not None and endurance not in ENDURANCE_MODES:
            raise ScenarioError(key("endurance"), endurance,
                                "one of " + ", ".join(repr(o) for o in ENDURANCE_MODES))
        if "endurance_limit" in d:  # the old boolean key
            old = d.pop("endurance_limit")
            if not isinstance(old, bool):
                raise ScenarioError(key("endurance_limit"), old,
                                    'true or false (or use endurance = "haibach" | '
                                    '"elementary" | "none")')
            implied = "elementary" if old else "none"
            if endurance is not None and endurance != implied:
                raise ScenarioError(key("endurance_limit"), old,
                                    f"not both: endurance = {endurance!r} contradicts it "
                                    f"(endurance_limit = {str(old).lower()} means "
                                    f"endurance = {implied!r}); drop endurance_limit")
            endurance = implied
        endurance = endurance or "haibach"
        d_comp = d.pop("component", {})
        component = _component(d_comp, key("component"))
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
            endurance=endurance,
            material_overrides=tuple(mat),
            cyclic=cyclic,
            component=component,
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
        try:
            mat0 = with_overrides(steel_817M40(cfg.cyclic), dict(cfg.material_overrides))
        except ValueError as e:
            raise ScenarioError(key("material"), dict(raw_mat),
                                f"a consistent material ({e})") from None
        try:
            cfg.material  # noqa: B018 -- builds the S-N curve: a factor set that breaks it
        except ValueError as e:
            raise ScenarioError(key("component"), dict(d_comp),
                                f"factors giving a valid S-N curve for Su = {mat0.Su:.4g} Pa "
                                f"({e})") from None
        if d:
            k = sorted(d)[0]
            raise ScenarioError(key(k), d[k], "no such key (known: influence, mapping, "
                                "stress_scale, equivalent, method, mean_stress, residue, "
                                "endurance, endurance_limit, material, component, "
                                "mesh_size_m, nodes, track_length_m, repeats_basis_m, "
                                "block_samples, live)")
        return cfg


COMPONENT_KEYS = ("enabled", "surface", "section_h_m", "section_b_m", "equivalent_diameter_m",
                  "loading", "reliability", "temperature_c", "kf", "knee_cycles")


def _component(raw, prefix: str) -> ComponentSpec | None:
    """Validate ``[fatigue.component]``; ScenarioError names the key (``prefix.<key>``)."""
    if not isinstance(raw, Mapping):
        raise ScenarioError(prefix, raw, "a table of component (Marin factor) settings")
    d = dict(raw)
    for k in d:
        if k not in COMPONENT_KEYS:
            raise ScenarioError(f"{prefix}.{k}", d[k], "a key among " + ", ".join(COMPONENT_KEYS))
    enabled = d.pop("enabled", True)
    if not isinstance(enabled, bool):
        raise ScenarioError(f"{prefix}.enabled", enabled, "true or false")
    defaults = ComponentSpec()

    def num(k: str, default, lo: float, hi: float, what: str):
        v = d.pop(k, default)
        if v is None and default is None:
            return None
        if (isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v)
                or not lo <= v <= hi):
            raise ScenarioError(f"{prefix}.{k}", v, what)
        return float(v)

    surface = d.pop("surface", defaults.surface)
    if surface not in SURFACE_FACTORS:
        raise ScenarioError(f"{prefix}.surface", surface,
                            "one of " + ", ".join(repr(o) for o in SURFACE_FACTORS))
    loading = d.pop("loading", defaults.loading)
    if loading not in LOADINGS:
        raise ScenarioError(f"{prefix}.loading", loading,
                            "one of " + ", ".join(repr(o) for o in LOADINGS))
    h = num("section_h_m", defaults.section_h_m, 1e-3, 0.3, "a section depth in m (0.001-0.3)")
    b = num("section_b_m", defaults.section_b_m, 1e-3, 0.3, "a section width in m (0.001-0.3)")
    d_e = num("equivalent_diameter_m", None, 2.79e-3, 0.254,
              "an equivalent diameter in m (0.00279-0.254, Shigley Eq 6-20)")
    if d_e is None and loading == "bending":
        de_rect = 0.808 * math.sqrt(h * b)
        if not 2.79e-3 <= de_rect <= 0.254:
            raise ScenarioError(f"{prefix}.section_h_m", h,
                                f"a section whose d_e = 0.808 sqrt(h b) = {de_rect:.4g} m lies "
                                "in 0.00279-0.254 m (Shigley Eq 6-20)")
    spec = ComponentSpec(
        surface=surface, section_h_m=h, section_b_m=b, d_e_m=d_e, loading=loading,
        reliability=num("reliability", defaults.reliability, 0.5, 0.999999,
                        "a reliability between 0.5 and 0.999999"),
        temperature_c=num("temperature_c", defaults.temperature_c, -60.0, 537.8,
                          "a temperature in °C (-60 to 537.8)"),
        kf=num("kf", defaults.kf, 1e-3, 2.0, "a factor in (0, 2]"),
        knee_cycles=num("knee_cycles", defaults.knee_cycles, 1e5, 1e8,
                        "a number of cycles between 1e5 and 1e8"),
    )
    return spec if enabled else None
