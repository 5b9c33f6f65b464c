"""Fatigue worker configuration: the ``[fatigue]`` section of a scenario, validated.

The keys, their defaults and units: docs/fatigue_keys.md (user reference; an unknown key or a
bad value is a :class:`~cosim.errors.ScenarioError` naming the key).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

from cosim.config import ConfigReader

from .lib.critical_plane import CRITICAL_PLANES, RANKING
from .lib.damage import METHODS
from .lib.equivalent_stress import EQUIVALENTS
from .lib.fkm import T_RANGE_C, FKMSpec, fkm_sn_curve
from .lib.life_models import ENDURANCE_MODES
from .lib.material import (
    ALIASES,
    CYCLIC_CURVES,
    ComponentSpec,
    Material,
    compatibility,
    component_sn_curve,
    material_sn_curve,
    with_overrides,
)
from .lib.mean_stress import MEAN_STRESS_METHODS
from .lib.sn_data import TabulatedSN
from .materials import database_material, material_names
from .strength_sections import read_component, read_fkm, read_sn_table

STRUCTURED_ARM = "builtin:structured"
"""``influence`` of the removed hand-meshed arm: refused, naming what to use instead."""
BUILTIN_PART = Path(__file__).parent / "parts" / "data" / "lower_arm.toml"
"""``influence = "builtin"``: the CAD lower arm (docs/parts.md), results shipped beside it."""

SN_METHODS = ("shigley", "fkm")
"""Named component S-N methods (``component.method``)."""

NODE_SETS = ("surface", "all")
RESIDUES = ("repeated", "half_cycles")


@dataclass(frozen=True)
class FatigueConfig:
    """Validated fatigue settings (keys and defaults: docs/fatigue_keys.md)."""

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
    material_name: str = "817M40"
    component: ComponentSpec | None = field(default_factory=ComponentSpec)
    sn_method: str = "shigley"
    survival_probability: float = 0.975
    fkm: FKMSpec = field(default_factory=FKMSpec)
    sn_table: TabulatedSN | None = None
    mesh_size_m: float | None = None
    nodes: str = "surface"
    track_length_m: float | None = None
    repeats_basis_m: float | None = None
    block_samples: int = 500
    screen: float = 0.1
    """Live screening fraction f (0: off; :mod:`.screening`): 0.1, measured on the CAD arm
    (13 778 nodes, Ch 6 pave, 2026-12-04) 102-108 us CPU per coupled step against 180-186
    unscreened (0.01: 131-139); the life, critical node, ten most damaged nodes and stress
    extremes stay bit-identical, every node that can reach 10 % of the largest damage is
    exact, the rest report an upper bound (their cycles NaN) in the live results."""
    live: bool | str = "auto"
    corner: str | None = None
    parts: tuple[str, ...] = ()
    """More parts (``parts``): their part files' absolute paths."""
    critical_plane: str | None = None
    """``equivalent = "findley"``: the critical-plane method run on the hot spots of the
    ``equivalent`` (then :data:`.critical_plane.RANKING`) pass; None: none."""
    base_dir: str = field(default=".", compare=False)

    @property
    def load_channel(self) -> str:
        """The plant channel of the arm loads this analysis takes: ``arm`` (a quarter car; the
        four-corner vehicle's front left), or ``arm_FL`` .. ``arm_RR`` by ``corner``."""
        return "arm" if self.corner is None else f"arm_{self.corner}"

    @property
    def material(self) -> Material:
        """The named material with the overrides, its S-N curve attached: the data curve
        (``sn_curve``), else the component's by ``component.method``, else the material's."""
        mat = with_overrides(self._base_material(), dict(self.material_overrides))
        sn: Any
        if self.sn_table is not None:
            sn = self.sn_table.with_endurance(self.endurance)
        elif self.component is None:
            sn = material_sn_curve(mat, self.endurance)
        elif self.sn_method == "fkm":
            sn = fkm_sn_curve(mat.Su, replace(self.fkm, knee_cycles=self.component.knee_cycles),
                              self.endurance, self.component.reliability,
                              self.component.temperature_c)
        else:
            sn = component_sn_curve(mat, self.component, self.endurance)
        return replace(mat, sn=sn)

    @property
    def curve_method(self) -> str | None:
        """The named component S-N method whose curve is in use ("shigley" or "fkm"); None
        for a data curve (``sn_curve``) or the material's line (component disabled)."""
        return None if self.component is None or self.sn_table is not None \
            else self.sn_method

    @property
    def mean_stress_rule(self) -> str:
        """The mean-stress rule every life of this config is computed with: FKM's Haigh
        diagram ("fkm", M_σ of `fkm`) for the FKM curve (the guideline's own rule, FKM 6th
        ed. Sec 4.4), else the scenario's ``mean_stress``."""
        return "fkm" if self.curve_method == "fkm" else self.mean_stress

    def at(self, method: str, P: float) -> FatigueConfig:
        """This config with the component curve of ``method`` at survival probability P:
        what each entry of ``sn_methods`` is computed with (its mean-stress rule follows:
        `mean_stress_rule`). The config itself is ``cfg.at(cfg.sn_method,
        cfg.component.reliability)``."""
        assert self.component is not None, "a component curve (component.enabled)"
        return replace(self, sn_method=method, component=replace(self.component, reliability=P))

    def _base_material(self) -> Material:
        """The named material with overridden E, ν, ρ, σu, σy applied before the estimated
        constants (UML σ'f, ε'f, K'; Shigley Se'), so that those follow them."""
        base = {k: v for k, v in self.material_overrides if k in ("E", "nu", "rho", "Su", "Sy")}
        return database_material(self.material_name, self.cyclic, base=base)

    def fatigue_properties(self) -> dict:
        """What the summary reports: the material constants with their sources, K'/n'
        compatibility, and the S-N curve with every factor (stresses in Pa)."""
        mat = self.material
        return {"material": mat.as_dict(), "material_source": dict(mat.source),
                "cyclic_compatibility": compatibility(mat),
                "sn_curve": mat.sn.as_dict() if mat.sn is not None else None}

    @property
    def influence_path(self) -> Path:
        p = Path(self.influence)
        return p if p.is_absolute() else Path(self.base_dir) / p

    def as_dict(self) -> dict:
        d = asdict(self)
        d["mapping"] = {c: {"file": f, "scale": s} for c, f, s in self.mapping}
        d["material"] = dict(self.material_overrides)
        d["material"]["cyclic"] = self.cyclic
        d["material"]["name"] = self.material_name
        d["sn_curve"] = None if self.sn_table is None else self.sn_table.as_dict()
        del d["sn_table"]
        if self.component is None:
            d["component"] = {"enabled": False}
        else:
            comp = asdict(self.component)
            comp["equivalent_diameter_m"] = comp.pop("d_e_m")
            d["component"] = {"enabled": True, **comp}
        d["fatigue_properties"] = self.fatigue_properties()
        d["mean_stress_applied"] = self.mean_stress_rule
        del d["material_overrides"], d["base_dir"], d["cyclic"], d["material_name"]
        if not self.parts:  # (a run without more parts: the settings as before)
            del d["parts"]
        if self.critical_plane is None:
            del d["critical_plane"]
        return d

    @classmethod
    def from_dict(cls, d: Mapping | None, key_prefix: str = "fatigue",
                  base_dir: str | Path = ".") -> FatigueConfig:
        """Validate a scenario section; a bad key or value raises ScenarioError(dotted key)."""
        r = ConfigReader(d or {}, key_prefix, FATIGUE_KEYS)
        influence = r.string("influence", "builtin",
                             expected='"builtin", a part file (*.toml) or a path to CSV files')
        if influence == STRUCTURED_ARM:
            raise r.error("influence", influence,
                          '"builtin" (the CAD lower arm, parts/data/lower_arm.toml) or a part '
                          'file (*.toml); the hand-meshed arm "builtin:structured" was removed '
                          'on 2026-12-06 (CHANGELOG.md)')
        mapping = _mapping(r.section("mapping", expected="a table channel -> case file"))
        if influence != "builtin" and not influence.lower().endswith(".toml") and not mapping:
            raise r.error("mapping", r.table("mapping"),
                          "a mapping of load channels to case files for imported tables")
        raw_mat = r.section("material", expected="a table of material overrides")
        cyclic = raw_mat.choice("cyclic", CYCLIC_CURVES, "uml")
        names = material_names()
        material_name = raw_mat.choice("name", names, "817M40")
        material_overrides = _material_overrides(raw_mat)
        raw_comp = r.section("component",
                             expected="a table of component (S-N method) settings")
        sn_method = raw_comp.choice("method", SN_METHODS, "shigley")
        survival = raw_comp.number("survival_probability", 0.975, lo=0.5, hi=0.999999,
                                   expected="a survival probability between 0.5 and 0.999999")
        fkm = read_fkm(raw_comp.section("fkm", expected="a table of FKM guideline inputs"))
        if sn_method == "fkm" and raw_comp.has("temperature_c"):
            T = raw_comp.number("temperature_c")
            if not T_RANGE_C[0] <= T <= T_RANGE_C[1]:
                raise raw_comp.error("temperature_c", T,
                                     f"a temperature the FKM guideline covers for steel "
                                     f"({T_RANGE_C[0]:g} to {T_RANGE_C[1]:g} °C) with "
                                     'method = "fkm"')
        eq = r.choice("equivalent", (*EQUIVALENTS, *CRITICAL_PLANES), "abs_max_principal")
        cfg = cls(
            influence=influence,
            mapping=mapping,
            stress_scale=r.number("stress_scale", 1.0, positive=True),
            equivalent=RANKING if eq in CRITICAL_PLANES else eq,
            critical_plane=eq if eq in CRITICAL_PLANES else None,
            method=r.choice("method", METHODS, "stress_life"),
            mean_stress=r.choice("mean_stress", MEAN_STRESS_METHODS, "goodman"),
            residue=r.choice("residue", RESIDUES, "repeated"),
            endurance=_endurance(r),
            material_overrides=material_overrides,
            cyclic=cyclic,
            material_name=material_name,
            component=read_component(raw_comp),
            sn_method=sn_method,
            survival_probability=survival,
            fkm=fkm,
            sn_table=read_sn_table(r, material_name),
            mesh_size_m=r.optional_number("mesh_size_m", lo=0.002, hi=0.1, unit="m"),
            nodes=r.choice("nodes", NODE_SETS, "surface"),
            track_length_m=r.optional_number("track_length_m", positive=True),
            repeats_basis_m=r.optional_number("repeats_basis_m", positive=True),
            block_samples=r.integer("block_samples", 500, lo=1),
            screen=r.number("screen", 0.1, lo=0.0, hi=1.0, hi_open=True),
            live=_live(r),
            corner=r.choice("corner", CORNERS) if r.has("corner") else None,
            parts=_parts(r, base_dir),
            base_dir=str(base_dir),
        )
        try:
            mat0 = with_overrides(cfg._base_material(), dict(cfg.material_overrides))
        except ValueError as e:
            raise r.error("material", dict(raw_mat.cfg),
                          f"a consistent material ({e})") from None
        try:
            cfg.material  # noqa: B018 -- builds the S-N curve: a factor set that breaks it
        except ValueError as e:
            raise r.error("component", dict(r.table("component")),
                          f"factors giving a valid S-N curve for Su = {mat0.Su:.4g} Pa "
                          f"({e})") from None
        return cfg


FATIGUE_KEYS = ("influence", "mapping", "stress_scale", "equivalent", "method", "mean_stress",
                "residue", "endurance", "endurance_limit", "material", "component", "sn_curve",
                "mesh_size_m", "nodes", "track_length_m", "repeats_basis_m", "block_samples",
                "screen", "live", "corner", "parts")
"""The keys of ``[fatigue]`` (docs/fatigue_keys.md)."""
CORNERS = ("FL", "FR", "RL", "RR")
"""``corner``: whose lower arm, on the four-corner vehicle (its plant/arm_<corner>)."""


SHIPPED_PARTS = Path(__file__).parent / "parts" / "data"
"""Where ``parts = ["<name>"]`` finds a shipped part file (``<name>.toml``)."""


def _parts(r: ConfigReader, base_dir: str | Path) -> tuple[str, ...]:
    """``parts``: each a shipped part's name or a part file (relative: to ``base_dir``),
    resolved to an existing file's absolute path; none twice."""
    raw = r.value("parts", [])
    expected = ('a list of part names (e.g. "upper_arm", shipped in nodes/fatigue/parts/'
                'data/) or part files (*.toml)')
    if not isinstance(raw, list) or not all(isinstance(v, str) and v for v in raw):
        raise r.error("parts", raw, expected)
    out: list[str] = []
    for v in raw:
        if not v.lower().endswith(".toml"):
            path = SHIPPED_PARTS / f"{v}.toml"
        else:
            path = Path(v)
            path = path if path.is_absolute() else Path(base_dir) / path
        if not path.is_file():
            known = sorted(p.stem for p in SHIPPED_PARTS.glob("*.toml")
                           if p.stem != "lower_arm_cad")
            raise r.error("parts", raw, f"{expected}; {v!r}: no such part (shipped: "
                                        f"{', '.join(known)})")
        p = str(path.resolve())
        if p in out:
            raise r.error("parts", raw, f"{expected}, each once ({v!r} twice)")
        out.append(p)
    return tuple(out)


def _mapping(r: ConfigReader) -> tuple[tuple[str, str, float], ...]:
    """``[fatigue.mapping]``: channel -> (channel, case file, scale)."""
    mapping: list[tuple[str, str, float]] = []
    for ch in r.names():
        spec = r.value(ch)
        if isinstance(spec, str):
            mapping.append((ch, spec, 1.0))
        elif isinstance(spec, Mapping) and isinstance(spec.get("file"), str):
            extra = set(spec) - {"file", "scale"}
            sc = spec.get("scale", 1.0)
            if extra or isinstance(sc, bool) or not isinstance(sc, (int, float)):
                raise r.error(ch, dict(spec), '{file = "<csv>", scale = <number>}')
            mapping.append((ch, spec["file"], float(sc)))
        else:
            raise r.error(ch, spec, 'a file name or {file = "<csv>", scale = <number>}')
    return tuple(mapping)


def _material_overrides(r: ConfigReader) -> tuple[tuple[str, float], ...]:
    """``[fatigue.material]`` besides ``cyclic``: (property name, value in SI units)."""
    r.only([*ALIASES, "cyclic", "name"])
    mat: list[tuple[str, float]] = []
    for mk in r.names():
        if mk in ("cyclic", "name"):
            continue
        mv = r.number(mk, expected="a finite number (SI units)")
        name = ALIASES[mk]
        if name in ("b", "c") and mv >= 0:
            raise r.error(mk, mv, "a negative exponent")
        if name not in ("b", "c") and mv <= 0:
            raise r.error(mk, mv, "a number > 0")
        if name == "nu" and not mv < 0.5:
            raise r.error(mk, mv, "a Poisson's ratio < 0.5")
        mat.append((name, mv))
    return tuple(mat)


def _endurance(r: ConfigReader) -> str:
    """``endurance``, or what the old boolean ``endurance_limit`` means (not both)."""
    endurance = r.choice("endurance", ENDURANCE_MODES) if r.has("endurance") else None
    if r.has("endurance_limit"):
        old = r.value("endurance_limit")
        if not isinstance(old, bool):
            raise r.error("endurance_limit", old, 'true or false (or use endurance = '
                          '"haibach" | "elementary" | "none")')
        implied = "elementary" if old else "none"
        if endurance is not None and endurance != implied:
            raise r.error("endurance_limit", old,
                          f"not both: endurance = {endurance!r} contradicts it "
                          f"(endurance_limit = {str(old).lower()} means "
                          f"endurance = {implied!r}); drop endurance_limit")
        endurance = implied
    return endurance or "haibach"


def _live(r: ConfigReader) -> bool | str:
    live = r.value("live", "auto")
    if not (isinstance(live, bool) or live == "auto"):
        raise r.error("live", live, 'true, false or "auto"')
    return live
