"""#31: ``fatigue.corner`` picks whose lower arm the live fatigue node takes on the four-corner
vehicle (plant/arm_<C>); without it, plant/arm (a quarter car's, the vehicle's FL)."""

from __future__ import annotations

import pytest

from cosim.errors import ScenarioError
from nodes.fatigue.config import FatigueConfig
from nodes.fatigue.node import preflight


def _scenario(**fatigue) -> dict:
    return {"run": {"mode": "distributed"}, "fatigue": fatigue}


def test_the_corner_names_the_plant_channel_and_the_node_joins_only_if_the_plant_has_it() -> None:
    assert FatigueConfig.from_dict({}).load_channel == "arm"
    assert FatigueConfig.from_dict({"corner": "RR"}).load_channel == "arm_RR"
    four = ["state", "response", "arm", "arm_FL", "arm_FR", "arm_RL", "arm_RR"]
    assert preflight(_scenario(corner="FR"), four)
    assert not preflight(_scenario(corner="FR"), ["state", "response", "arm"])  # a quarter car
    assert preflight(_scenario(), ["state", "response", "arm"])
    with pytest.raises(ScenarioError, match="no lower-arm loads"):
        preflight(_scenario(corner="FR", live=True), ["state", "response", "arm"])


def test_a_corner_that_is_not_one_is_refused_by_key() -> None:
    with pytest.raises(ScenarioError, match="fatigue.corner.*'FL', 'FR', 'RL', 'RR'"):
        FatigueConfig.from_dict({"corner": "front_left"})
