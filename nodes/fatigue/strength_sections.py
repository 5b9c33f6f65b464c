"""The strength sections of a scenario's ``[fatigue]``, read and validated: the component's
Marin factors (``[fatigue.component]``), its FKM guideline inputs
(``[fatigue.component.fkm]``) and a tabulated S-N curve (``[fatigue.sn_curve]``, or the
material's ``sn`` table in the database). Each reader takes a
:class:`cosim.config.ConfigReader` of its section and raises a ScenarioError that names the
bad key; :mod:`.config` assembles them into the :class:`.config.FatigueConfig`.
"""

from __future__ import annotations

import math
from typing import Any

from cosim.config import ConfigReader
from cosim.errors import ScenarioError

from .lib.fkm import FKMSpec
from .lib.material import LOADINGS, SURFACE_FACTORS, ComponentSpec
from .lib.sn_data import TabulatedSN, ncode_curve, points_curve

COMPONENT_KEYS = ("enabled", "surface", "section_h_m", "section_b_m", "equivalent_diameter_m",
                  "loading", "reliability", "temperature_c", "kf", "knee_cycles", "method",
                  "survival_probability", "fkm")
FKM_KEYS = tuple(f for f in FKMSpec.__dataclass_fields__ if f != "knee_cycles")
SN_TABLE_KEYS = ("type", "points", "stress", "sri1_pa", "b1", "nc1", "b2", "name", "source")


def read_fkm(r: ConfigReader) -> FKMSpec:
    """``[fatigue.component.fkm]``: the FKM inputs; a bad value names its key."""
    r.only(FKM_KEYS)
    kw: dict[str, Any] = {}
    for k in FKM_KEYS:
        if r.has(k):
            kw[k] = r.number(k, expected="a finite number (see fkm.FKMSpec)")
    try:
        return FKMSpec(**kw)
    except ValueError as e:
        bad = str(e).split(" ", 1)[0]
        raise r.error(bad if bad in kw else "fkm", kw.get(bad, kw), str(e)) from None


def read_sn_table(r: ConfigReader, material_name: str) -> TabulatedSN | None:
    """``[fatigue.sn_curve]`` (or the named material's ``sn`` in the database)."""
    from .materials import load_database

    if r.has("sn_curve"):
        t = r.section("sn_curve", expected="a table (type = \"points\" | \"segments\")")
        key_name = r.key("sn_curve")
    else:
        raw = load_database()[material_name].get("sn")
        if not raw:
            return None
        t = ConfigReader(raw, f"materials.toml [{material_name}.sn]")
        key_name = t.name
    t.only(SN_TABLE_KEYS)
    kind = t.choice("type", ("points", "segments"))
    name = t.string("name", f"S-N {kind} ({key_name})")
    source = t.string("source", "scenario", empty=True)
    try:
        if kind == "points":
            pts = t.value("points")
            if not isinstance(pts, list) or not all(
                    isinstance(p, list) and len(p) == 2 for p in pts):
                raise t.error("points", pts, "a list of [N cycles, S Pa] pairs")
            return points_curve(pts, t.choice("stress", ("amplitude", "range"), "amplitude"),
                                name=name, source=source)
        return ncode_curve(t.number("sri1_pa", positive=True), t.number("b1", hi=0.0),
                           t.number("nc1", lo=1.0), t.number("b2", 0.0, hi=0.0),
                           name=name, source=source)
    except (ValueError, TypeError) as e:
        if isinstance(e, ScenarioError):
            raise
        raise t.error("points" if kind == "points" else "b1", dict(t.cfg), str(e)) from None


def read_component(r: ConfigReader) -> ComponentSpec | None:
    """Validate ``[fatigue.component]``'s Marin keys; ScenarioError names the key."""
    r.only(COMPONENT_KEYS)
    enabled = r.boolean("enabled", True)
    defaults = ComponentSpec()
    surface = r.choice("surface", SURFACE_FACTORS, defaults.surface)
    loading = r.choice("loading", LOADINGS, defaults.loading)
    h = r.number("section_h_m", defaults.section_h_m, lo=1e-3, hi=0.3,
                 expected="a section depth in m (0.001-0.3)")
    b = r.number("section_b_m", defaults.section_b_m, lo=1e-3, hi=0.3,
                 expected="a section width in m (0.001-0.3)")
    d_e = r.optional_number("equivalent_diameter_m", lo=2.79e-3, hi=0.254,
                            expected="an equivalent diameter in m (0.00279-0.254, "
                                     "Shigley Eq 6-20)")
    if d_e is None and loading == "bending":
        de_rect = 0.808 * math.sqrt(h * b)
        if not 2.79e-3 <= de_rect <= 0.254:
            raise r.error("section_h_m", h,
                          f"a section whose d_e = 0.808 sqrt(h b) = {de_rect:.4g} m lies "
                          "in 0.00279-0.254 m (Shigley Eq 6-20)")
    spec = ComponentSpec(
        surface=surface, section_h_m=h, section_b_m=b, d_e_m=d_e, loading=loading,
        reliability=r.number("reliability", defaults.reliability, lo=0.5, hi=0.999999,
                             expected="a reliability between 0.5 and 0.999999"),
        temperature_c=r.number("temperature_c", defaults.temperature_c, lo=-60.0, hi=537.8,
                               expected="a temperature in °C (-60 to 537.8)"),
        kf=r.number("kf", defaults.kf, lo=1e-3, hi=2.0, expected="a factor in (0, 2]"),
        knee_cycles=r.number("knee_cycles", defaults.knee_cycles, lo=1e5, hi=1e8,
                             expected="a number of cycles between 1e5 and 1e8"),
    )
    return spec if enabled else None
