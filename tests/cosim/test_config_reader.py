"""cosim.config.ConfigReader: each check, and the dotted key in every message."""

from __future__ import annotations

import math

import pytest

from cosim.config import REQUIRED, ConfigReader, describe_range
from cosim.errors import ScenarioError


def _err(call, *args, **kw) -> ScenarioError:
    with pytest.raises(ScenarioError) as e:
        call(*args, **kw)
    assert e.value.exit_code == 2
    return e.value


def test_a_table_must_be_a_mapping():
    e = _err(ConfigReader, [1, 2], "road")
    assert e.key == "road" and "a table" in str(e)


def test_number_accepts_int_and_float_returns_float():
    r = ConfigReader({"a": 3, "b": 2.5}, "s")
    a = r.number("a")
    assert a == 3.0 and type(a) is float
    assert r.number("b", lo=0.0, hi=2.5) == 2.5
    assert type(r.number("absent", 7)) is float and r.number("absent", 7) == 7.0


@pytest.mark.parametrize("value", [True, False, "1.0", None, [1.0], {"x": 1}])
def test_bool_and_non_numbers_are_not_numbers(value):
    e = _err(ConfigReader({"x": value}, "tyre").number, "x")
    assert e.key == "tyre.x" and e.value is value and "a number" in str(e)


@pytest.mark.parametrize("value", [math.inf, -math.inf, math.nan])
def test_non_finite_numbers_are_refused(value):
    e = _err(ConfigReader({"x": value}, "tyre").number, "x")
    assert e.key == "tyre.x"


@pytest.mark.parametrize("kw,value,text", [
    ({"lo": 0.0}, -1e-9, ">= 0"),
    ({"positive": True}, 0.0, "> 0"),
    ({"lo": 0.0, "lo_open": True}, 0, "> 0"),
    ({"hi": 1.0}, 1.5, "<= 1"),
    ({"hi": 1.0, "hi_open": True}, 1.0, "< 1"),
    ({"lo": 0.0, "hi": 0.6, "unit": "A"}, 0.7, "in [0, 0.6] A"),
    ({"lo": 0.0, "hi": 0.5, "lo_open": True, "hi_open": True}, 0.5, "in (0, 0.5)"),
])
def test_number_ranges(kw, value, text):
    e = _err(ConfigReader({"x": value}, "controller").number, "x", **kw)
    assert e.key == "controller.x" and f"a number {text}" in str(e)


def test_range_bounds_are_inclusive_unless_open():
    r = ConfigReader({"x": 0.0, "y": 1.0}, "s")
    assert r.number("x", lo=0.0) == 0.0 and r.number("y", hi=1.0) == 1.0


def test_a_missing_required_key_is_named_and_said_missing():
    e = _err(ConfigReader({}, "road").number, "speed_kmh", positive=True)
    assert e.key == "road.speed_kmh" and e.value is None
    assert "a number > 0 (missing)" in str(e)
    assert _err(ConfigReader({}, "road").number, "x", REQUIRED).key == "road.x"


def test_a_default_is_not_checked_against_the_range():
    # the defaults are the code's own values; only what the user gives is checked
    assert ConfigReader({}, "s").number("x", 5.0, hi=1.0) == 5.0


def test_expected_text_replaces_the_generated_one():
    e = _err(ConfigReader({"kf": 3.0}, "fatigue.component").number, "kf", lo=1e-3, hi=2.0,
             expected="a factor in (0, 2]")
    assert str(e) == "scenario key 'fatigue.component.kf': got 3.0, expected a factor in (0, 2]"


def test_optional_number():
    r = ConfigReader({"x": 2}, "s")
    assert r.optional_number("absent", positive=True) is None
    assert r.optional_number("x", positive=True) == 2.0
    assert _err(ConfigReader({"x": -2}, "s").optional_number, "x", positive=True).key == "s.x"


@pytest.mark.parametrize("value", [True, 2.0, "2", -1, 10001])
def test_integer_refuses_bool_float_and_out_of_range(value):
    e = _err(ConfigReader({"n": value}, "tyre").integer, "n", lo=0, hi=10000)
    assert e.key == "tyre.n" and "an integer in [0, 10000]" in str(e)


def test_integer_ok():
    r = ConfigReader({"n": 4}, "tyre")
    assert r.integer("n", lo=1) == 4 and r.integer("seed", 0, lo=0) == 0


def test_choice():
    r = ConfigReader({"law": "tss1", "shape": 1}, "controller")
    assert r.choice("law", ("passive", "tss1")) == "tss1"
    assert r.choice("velocity", ("relative", "damper"), "relative") == "relative"
    e = _err(r.choice, "law", ("passive", "skyhook"))
    assert e.key == "controller.law" and "one of 'passive', 'skyhook'" in str(e)
    assert _err(r.choice, "shape", ("1", "2")).key == "controller.shape"  # 1 is not '1'
    assert "(missing)" in str(_err(r.choice, "absent", ("a",)))


def test_a_choice_is_a_string():
    assert _err(ConfigReader({"x": True}, "s").choice, "x", ("True",)).key == "s.x"


def test_fatigue_live_one_is_not_true():
    # 1 == True in Python: the old check took live = 1 for live = true
    from nodes.fatigue.config import FatigueConfig

    e = _err(FatigueConfig.from_dict, {"live": 1})
    assert e.key == "fatigue.live" and 'true, false or "auto"' in str(e)
    assert FatigueConfig.from_dict({"live": True}).live is True


def test_boolean():
    r = ConfigReader({"on": True, "one": 1, "s": "true"}, "vehicle")
    assert r.boolean("on") is True and r.boolean("absent", False) is False
    for key in ("one", "s"):
        e = _err(r.boolean, key)
        assert e.key == f"vehicle.{key}" and "true or false" in str(e)


def test_string():
    r = ConfigReader({"path": "a.csv", "empty": "", "num": 3}, "road")
    assert r.string("path") == "a.csv" and r.string("absent", "x") == "x"
    assert r.string("empty", empty=True) == ""
    assert "a non-empty string" in str(_err(r.string, "empty"))
    assert _err(r.string, "num", expected="a file path").key == "road.num"
    assert r.optional_string("absent") is None and r.optional_string("path") == "a.csv"


def test_number_list():
    r = ConfigReader({"band": [0.01, 3], "three": [1, 2, 3], "flag": [1, True],
                      "inf": [1, math.inf], "text": "0.01, 3"}, "road")
    band = r.number_list("band", length=2)
    assert band == [0.01, 3.0] and all(type(x) is float for x in band)
    assert r.number_list("absent", (1, 2)) == [1.0, 2.0]
    for key in ("three", "flag", "inf", "text"):
        e = _err(r.number_list, key, length=2)
        assert e.key == f"road.{key}" and "a list of 2 numbers" in str(e)


def test_sub_tables_carry_the_dotted_name():
    r = ConfigReader({"damper": {"I_max": 1.0}, "bad": 3}, "controller")
    d = r.section("damper", ("I_max",))
    e = _err(d.number, "I_max", lo=0.0, hi=0.6)
    assert e.key == "controller.damper.I_max"
    assert r.section("absent").names() == []
    assert _err(r.section, "bad").key == "controller.bad"
    assert dict(r.table("damper")) == {"I_max": 1.0}
    assert _err(r.table, "bad").key == "controller.bad"


def test_a_list_of_tables_names_each_item():
    r = ConfigReader({"events": [{"height": 0.1}, {"height": "x"}], "none": [],
                      "junk": [{"height": 1}, 3]}, "road")
    first, second = r.sections("events")
    assert first.number("height") == 0.1
    assert _err(second.number, "height").key == "road.events[1].height"
    assert _err(r.sections, "none").key == "road.none"
    assert _err(r.sections, "junk").key == "road.junk[1]"
    assert _err(r.sections, "absent").key == "road.absent"


def test_unknown_keys_are_named_listed_and_a_close_match_suggested():
    e = _err(ConfigReader, {"law": "skyhook", "c_skyy": 2500.0}, "controller",
             ("law", "c_sky", "c_min"))
    assert e.key == "controller.c_skyy" and e.value == 2500.0
    assert "one of the keys ['c_min', 'c_sky', 'law']" in str(e)
    assert "did you mean 'c_sky'?" in str(e)
    far = _err(ConfigReader, {"zzzz": 1}, "controller", ("law",))
    assert "did you mean" not in str(far)


def test_unlisted_keys_are_accepted_but_not_offered():
    r = ConfigReader({"h": 0.001, "n_steps": 10}, "run")
    r.only(("h", "t_end"), unlisted=("n_steps",))
    e = _err(ConfigReader({"dirr": 1}, "run").only, ("h",), unlisted=("dir",))
    assert "n_steps" not in str(e) and "'dir'" not in str(e) and e.key == "run.dirr"


def test_finish_refuses_what_was_neither_read_nor_declared():
    r = ConfigReader({"G": 1e-6, "wavines": 2.5}, "road")
    assert r.number("G", positive=True) == 1e-6
    r.number("waviness", 2.5)  # read (absent, default): known
    e = _err(r.finish)
    assert e.key == "road.wavines" and "did you mean 'waviness'?" in str(e)
    ok = ConfigReader({"G": 1e-6, "note": "x"}, "road")
    ok.number("G")
    ok.finish(also=("note",))


def test_a_top_level_table_names_its_keys_alone():
    assert _err(ConfigReader({"x": "a"}, "").number, "x").key == "x"


def test_error_helper_names_the_dotted_key():
    e = ConfigReader({}, "controller").error("c_hard", 100.0, "a number >= c_soft")
    assert isinstance(e, ScenarioError) and e.key == "controller.c_hard"


def test_describe_range():
    assert describe_range() == "" and describe_range(unit="A") == " (A)"
    assert describe_range(0.0, 0.6, lo_open=True, unit="A") == " in (0, 0.6] A"
    assert describe_range(hi=5.0, hi_open=True) == " < 5"


# Every model factory reads through the reader: a typo anywhere names the dotted key and
# suggests the key that was meant.
def _factories():
    from cosim.scenario import validate_common
    from nodes.controller.laws import build_controller
    from nodes.fatigue.config import FatigueConfig
    from nodes.plant.models import build_plant_model
    from nodes.tyre_road.config import build_road, build_tyre

    return [
        (lambda: validate_common({"run": {"t_endd": 2.0}}), "run.t_endd", "t_end"),
        (lambda: build_controller({"law": "passive", "cc": 1500.0}, 1, 0.001),
         "controller.cc", "c"),
        (lambda: build_controller({"law": "tss2", "damper": {"I_maxx": 0.5}}, 1, 0.001),
         "controller.damper.I_maxx", "I_max"),
        (lambda: build_road({"type": "events", "speed_kmh": 10.0,
                             "events": [{"type": "step", "height": 0.01},
                                        {"type": "bump", "heigth": 0.01, "length": 1.0}]}),
         "road.events[1].heigth", "height"),
        (lambda: build_tyre({"model": "point_contact", "stifness": 1e5}), "tyre.stifness",
         "stiffness"),
        (lambda: build_plant_model({"model": "quarter_car_lumped", "sprung_mas": 300.0}),
         "vehicle.sprung_mas", "sprung_mass"),
        (lambda: FatigueConfig.from_dict({"mesh_size": 0.02}), "fatigue.mesh_size",
         "mesh_size_m"),
        (lambda: FatigueConfig.from_dict({"component": {"surfce": "forged"}}),
         "fatigue.component.surfce", "surface"),
    ]


@pytest.mark.parametrize("case", range(8))
def test_every_factory_names_the_typo_and_suggests_the_key(case):
    build, key, meant = _factories()[case]
    e = _err(build)
    assert e.key == key and f"'{key}'" in str(e) and f"did you mean '{meant}'?" in str(e)
