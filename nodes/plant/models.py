"""Plant model factory: the ``[vehicle]`` scenario section -> a :class:`PlantModel`.

``model`` selects the model; the other keys are the fields of its params dataclass (SI
units; missing ones take its defaults): ``quarter_car_lumped`` (:class:`.quarter_car_lumped.
LumpedQuarterCarParams`, Ch. 3 Table 3.1), ``quarter_car_double_wishbone``
(:class:`.double_wishbone.DoubleWishboneParams`, Table 4.2, plus ``corner``: the corner file,
default the built-in ``cosim/corners/mpv_front.toml``, a relative path relative to the
scenario file; the params override the file's masses, torsion bar and bumper),
``full_vehicle_7dof`` (:class:`.full_vehicle_7dof.FullVehicleParams`, Table 4.4,
``mass_basis`` "corner" | "axle"), ``full_vehicle_double_wishbone``
(:class:`.full_vehicle_dw.FullVehicleDWParams`, plus ``front``, ``rear``: the left corners'
files, the rear defaulting to the front, and ``driver``: a table, ``speed`` [[t, v], ...] m/s,
``steer`` [[t, delta], ...] rad or ``radius`` m, ``brake_balance``, ``driven``,
:mod:`.driver`; with ``[tyre] model = "magic_formula"`` its tyres act in 3-D).

Numbers must be > 0, switches true or false; bad keys or values raise
:class:`cosim.errors.ScenarioError`. (Damper and tyre live in the controller and tyre nodes.)
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

from cosim import corner as corner_file
from cosim.config import ConfigReader
from cosim.corner import Corner
from cosim.errors import ScenarioError

from .model import PlantModel

MODELS = ("quarter_car_lumped", "quarter_car_double_wishbone", "full_vehicle_7dof",
          "full_vehicle_double_wishbone")


def _params(cls, r: ConfigReader, choices: dict[str, tuple[str, ...]] | None = None,
            base: Any = None, extra: tuple[str, ...] = ()):
    """``cls(**kwargs)`` from the keys the table gives (the dataclass, or ``base``'s values,
    fill the others); ``extra``: keys of the table read elsewhere."""
    fields = {f.name: f for f in dataclasses.fields(cls)}
    r.only(["model", *extra, *fields])
    kwargs: dict[str, Any] = {}
    for key in r.names():
        if key == "model" or key in extra:
            continue
        if choices and key in choices:
            kwargs[key] = r.choice(key, choices[key])
        elif isinstance(fields[key].default, bool):
            kwargs[key] = r.boolean(key)
        else:
            kwargs[key] = r.number(key, positive=True)
    return cls(**kwargs) if base is None else dataclasses.replace(base, **kwargs)


def build_plant_model(cfg: Mapping[str, Any], key_prefix: str = "vehicle") -> PlantModel:
    """Build the plant model named by ``cfg["model"]`` with the parameters in ``cfg``."""
    r = ConfigReader(cfg, key_prefix)
    model = r.choice("model", MODELS)
    if model == "quarter_car_lumped":
        from .quarter_car_lumped import LumpedQuarterCar, LumpedQuarterCarParams
        return LumpedQuarterCar(_params(LumpedQuarterCarParams, r))
    if model == "full_vehicle_7dof":
        from .full_vehicle_7dof import FullVehicle7DOF, FullVehicleParams
        return FullVehicle7DOF(_params(FullVehicleParams, r,
                                       {"mass_basis": ("corner", "axle")}))
    if model == "full_vehicle_double_wishbone":
        from .full_vehicle_dw import FullVehicleDoubleWishbone, FullVehicleDWParams
        front = read_corner(r, "front")
        rear = read_corner(r, "rear") if r.has("rear") else front
        fv = _params(FullVehicleDWParams, r, extra=("front", "rear", "driver"))
        drv = read_driver(r) if r.has("driver") else None
        try:
            return FullVehicleDoubleWishbone(fv, front=front, rear=rear, driver=drv)
        except ValueError as exc:
            raise ScenarioError(r.key("front"), front.source, str(exc)) from None
    from .double_wishbone import DoubleWishboneCorner, DoubleWishboneParams  # the third model
    corner = read_corner(r)
    params = _params(DoubleWishboneParams, r, base=DoubleWishboneParams.from_corner(corner),
                     extra=("corner",))
    try:
        return DoubleWishboneCorner(params, corner=corner)
    except ValueError as exc:  # what the PyBullet corner cannot build from that file
        raise ScenarioError(r.key("corner"), corner.source, str(exc)) from None


def read_corner(r: ConfigReader, key: str = "corner") -> Corner:
    """The ``key``'s corner file (the built-in MPV corner when absent or ``"builtin"``); a
    bad file raises :class:`cosim.errors.InputFileError`."""
    path = r.string(key, "builtin")
    if path == "builtin":
        return corner_file.builtin()
    return corner_file.load(path, r.key(key))


def read_driver(r: ConfigReader) -> dict[str, Any]:
    """The ``vehicle.driver`` table as :class:`.driver.Driver`'s keyword arguments (the
    vehicle's mass, wheel radius and wheelbase come from the model); bad keys or values
    raise :class:`ScenarioError` naming the key."""
    key = r.key("driver")
    cfg = r.cfg["driver"]
    if not isinstance(cfg, Mapping):
        raise ScenarioError(key, cfg, "a table: speed, steer or radius, brake_balance, driven")
    d = ConfigReader(cfg, key)
    d.only(["speed", "steer", "radius", "brake_balance", "driven"])
    out: dict[str, Any] = {}
    for name in ("speed", "steer"):
        if d.has(name):
            pts = d.cfg[name]
            ok = isinstance(pts, list) and pts and all(
                isinstance(q, list) and len(q) == 2 and all(
                    isinstance(x, (int, float)) and not isinstance(x, bool) for x in q)
                for q in pts)
            if not ok:
                raise ScenarioError(d.key(name), pts, "a list of [t, value] pairs")
            out[name] = [(float(q[0]), float(q[1])) for q in pts]
    if "speed" not in out:
        raise ScenarioError(d.key("speed"), None, "the speed profile [[t, v], ...] in m/s")
    if d.has("radius"):
        out["radius"] = d.number("radius")
    if d.has("brake_balance"):
        out["brake_balance"] = d.number("brake_balance", lo=0.0, hi=1.0)
    if d.has("driven"):
        out["driven"] = d.choice("driven", ("front", "rear", "all"))
    try:
        from .driver import Driver
        Driver(mass=1.0, wheel_radius=1.0, wheelbase=1.0, **out)
    except ValueError as exc:
        raise ScenarioError(key, cfg, str(exc)) from None
    return out
