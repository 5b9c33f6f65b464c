"""Plant model factory: the ``[vehicle]`` scenario section -> a :class:`PlantModel`.

``model`` selects the model; the other keys are its parameters (SI units):

* ``quarter_car_lumped`` (Ch. 3 Table 3.1 defaults; Ch. 4 Table 4.3 via the scenario):
  ``sprung_mass``, ``unsprung_mass``, ``spring_stiffness``.
* ``quarter_car_double_wishbone`` (Table 4.2): ``body_mass``, ``hub_mass``,
  ``lower_arm_mass``, ``upper_arm_mass``, ``tie_rod_mass``, ``torsion_stiffness_nm_per_deg``;
  its jounce bumper (:mod:`.bump_stop`): ``bump_stop`` (true/false, default true),
  ``bump_stop_clearance`` [m], ``bump_stop_initial_rate`` [N/m], ``bump_stop_stroke`` [m].
* ``full_vehicle_7dof`` (Table 4.4): ``sprung_mass_front``, ``sprung_mass_rear``,
  ``unsprung_mass``, ``spring_stiffness``, ``pitch_inertia``, ``roll_inertia``, ``wheelbase``,
  ``track``, ``mass_basis`` ("corner" | "axle").

Missing parameters take the defaults of the model's params dataclass. Numbers must be > 0,
switches true or false. Bad keys or values raise :class:`cosim.errors.ScenarioError`.
(Damper and tyre live in the controller and tyre nodes.)
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

from cosim.errors import ScenarioError

from .model import PlantModel

MODELS = ("quarter_car_lumped", "quarter_car_double_wishbone", "full_vehicle_7dof")


def _params(cls, cfg: Mapping, prefix: str, choices: dict[str, tuple[str, ...]] | None = None):
    fields = {f.name: f for f in dataclasses.fields(cls)}
    kwargs = {}
    for key, value in cfg.items():
        if key == "model":
            continue
        if key not in fields:
            raise ScenarioError(f"{prefix}.{key}", value,
                                f"one of the keys {sorted(['model', *fields])}")
        if choices and key in choices:
            if value not in choices[key]:
                raise ScenarioError(f"{prefix}.{key}", value, "one of " + ", ".join(
                    repr(c) for c in choices[key]))
        elif isinstance(fields[key].default, bool):
            if not isinstance(value, bool):
                raise ScenarioError(f"{prefix}.{key}", value, "true or false")
        elif isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
            raise ScenarioError(f"{prefix}.{key}", value, "a number > 0")
        else:
            value = float(value)
        kwargs[key] = value
    return cls(**kwargs)


def build_plant_model(cfg: Mapping, key_prefix: str = "vehicle") -> PlantModel:
    """Build the plant model named by ``cfg["model"]`` with the parameters in ``cfg``."""
    p = key_prefix
    if not isinstance(cfg, Mapping):
        raise ScenarioError(p, cfg, "a table")
    model = cfg.get("model")
    if model == "quarter_car_lumped":
        from .quarter_car_lumped import LumpedQuarterCar, LumpedQuarterCarParams
        return LumpedQuarterCar(_params(LumpedQuarterCarParams, cfg, p))
    if model == "full_vehicle_7dof":
        from .full_vehicle_7dof import FullVehicle7DOF, FullVehicleParams
        return FullVehicle7DOF(_params(FullVehicleParams, cfg, p,
                                       {"mass_basis": ("corner", "axle")}))
    if model == "quarter_car_double_wishbone":
        from .double_wishbone import DoubleWishboneCorner, DoubleWishboneParams
        return DoubleWishboneCorner(_params(DoubleWishboneParams, cfg, p))
    raise ScenarioError(f"{p}.model", model, "one of " + ", ".join(MODELS))
