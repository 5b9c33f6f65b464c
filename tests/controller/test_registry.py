"""The law registry: a law is one decorated function, found by name, validated like the rest."""

from __future__ import annotations

import sys
import textwrap

import numpy as np
import pytest

from cosim.errors import ScenarioError
from nodes.controller import registry
from nodes.controller.laws import LAWS, build_controller
from nodes.controller.registry import PRESETS, FunctionLaw, ParamInfo, lookup


def state(v_b, v_w, n=1):
    return {"z_b": np.zeros(n), "z_w": np.zeros(n), "v_b": np.full(n, v_b, dtype=float),
            "v_w": np.full(n, v_w, dtype=float)}


@pytest.fixture
def user_module(tmp_path, monkeypatch):
    """A law module outside the package, importable as ``my_laws`` (as a user would write)."""
    (tmp_path / "my_laws.py").write_text(textwrap.dedent('''
        import numpy as np
        from nodes.controller.registry import HARD, SOFT, Param, control_law

        @control_law("test_user_gain_law")
        def gain_law(t, v_b, v_rel, memory, *, gain: float = Param(lo=0.0, unit="N s/m"),
                     mode: str = Param("up", choices=("up", "down")), c_min=SOFT, c_max=HARD):
            """Clipped |v_b| gain; counts its calls in memory."""
            memory["calls"] = memory.get("calls", 0) + 1
            c = np.clip(gain * np.abs(v_b), c_min, c_max)
            return c * v_rel, c, {"calls": memory["calls"], "t_seen": t}

        def not_a_law(v_rel):
            return v_rel, 0.0
    '''))
    monkeypatch.syspath_prepend(str(tmp_path))
    yield "my_laws"
    sys.modules.pop("my_laws", None)
    registry.LAWS.pop("test_user_gain_law", None)


def test_a_user_law_is_named_by_module_and_function(user_module):
    ctl = build_controller({"law": "my_laws:gain_law", "gain": 20000.0}, 2, 0.001)
    assert isinstance(ctl, FunctionLaw) and ctl.law == "test_user_gain_law"
    out = ctl.step(0.5, state(0.1, 0.0, n=2))
    # c = clip(20000 * 0.1, 1500, 2368) = 2000; F = 2000 * (0 - 0.1)
    np.testing.assert_array_equal(out.c_eff, [2000.0, 2000.0])
    np.testing.assert_array_equal(out.F_d, [-200.0, -200.0])
    assert out.extra["t_seen"].tolist() == [0.5, 0.5]
    out = ctl.step(0.501, state(0.1, 0.0, n=2))
    assert out.extra["calls"].tolist() == [2.0, 2.0]  # memory kept between calls
    # once imported it is registered under its own name too
    assert build_controller({"law": "test_user_gain_law", "gain": 1.0}, 1, 0.001).law == \
        "test_user_gain_law"


@pytest.mark.parametrize(
    ("cfg", "key"),
    [
        ({"law": "my_laws:gain_law"}, "controller.gain"),  # required, no default
        ({"law": "my_laws:gain_law", "gain": -1.0}, "controller.gain"),
        ({"law": "my_laws:gain_law", "gain": 1.0, "mode": "sideways"}, "controller.mode"),
        ({"law": "my_laws:gain_law", "gain": 1.0, "c_min": 3000.0}, "controller.c_max"),
        ({"law": "my_laws:gain_law", "gain": 1.0, "preset": "x"}, "controller.preset"),
        ({"law": "my_laws:gain_law", "gain": 1.0, "gian": 1.0}, "controller.gian"),
        ({"law": "my_laws:not_a_law"}, "controller.law"),
        ({"law": "my_laws:missing"}, "controller.law"),
        ({"law": "no_such_module_xyz:law"}, "controller.law"),
    ],
)
def test_user_law_settings_are_validated_naming_the_key(user_module, cfg, key):
    with pytest.raises(ScenarioError) as err:
        build_controller(cfg, 1, 0.001)
    assert err.value.key == key


def test_preset_gives_the_soft_and_hard_defaults(user_module):
    ctl = build_controller({"law": "my_laws:gain_law", "gain": 1e9, "preset": "realistic"}, 1, 1e-3)
    assert ctl.settings["c_min"] == 3800.0 and ctl.settings["c_max"] == 6000.0
    assert ctl.step(0.0, state(0.1, 0.0)).c_eff[0] == 6000.0


def test_wrong_output_shape_or_type_is_a_clear_error():
    @registry.control_law("test_bad_shape")
    def bad(v_rel):
        """Returns three forces for one corner."""
        return np.zeros(3), 0.0

    @registry.control_law("test_bad_type")
    def bad2(v_rel):
        """Returns a bare number."""
        return 1.0

    try:
        with pytest.raises(ValueError, match="test_bad_shape.*shape"):
            build_controller({"law": "test_bad_shape"}, 1, 1e-3).step(0.0, state(0, 0))
        with pytest.raises(TypeError, match="test_bad_type"):
            build_controller({"law": "test_bad_type"}, 1, 1e-3).step(0.0, state(0, 0))
    finally:
        registry.LAWS.pop("test_bad_shape"), registry.LAWS.pop("test_bad_type")


def test_a_name_defined_twice_in_two_modules_is_refused():
    def clash(v_rel):
        return v_rel, 0.0

    clash.__module__ = "somewhere.else"
    with pytest.raises(ValueError, match="defined twice"):
        registry.control_law("tss1")(clash)


def example(p: ParamInfo):
    """A valid value of a setting: its default, else inside its range."""
    if p.preset:
        return PRESETS["lumped"][0 if p.preset == "soft" else 1]
    if not p.required:
        return p.default
    if p.choices:
        return p.choices[0]
    if p.lo is not None and p.hi is not None:
        return 0.5 * (p.lo + p.hi)
    return (p.lo or 0.0) + 1.0


def example_config(name: str) -> dict:
    """A valid ``[controller]`` table of a function law (required settings at examples)."""
    return {"law": name, **{k: example(p) for k, p in lookup(name).params.items()
                            if p.required}}


def test_every_function_law_builds_from_its_example_and_returns_one_value_per_corner():
    function_laws = [name for name, spec in LAWS.items() if spec.fn is not None]
    assert {"passive", "tss1", "skyhook", "groundhook", "hybrid"} <= set(function_laws)
    rng = np.random.default_rng(2)
    for name in function_laws:
        ctl = build_controller(example_config(name), 4, 0.001)
        for k in range(3):
            s = {"z_b": rng.normal(0, .01, 4), "z_w": rng.normal(0, .01, 4),
                 "v_b": rng.normal(0, .3, 4), "v_w": rng.normal(0, .6, 4)}
            out = ctl.step(k * 0.001, s)
            assert out.F_d.shape == (4,) and out.c_eff.shape == (4,), name
            assert np.all(np.isfinite(out.F_d)), name


def test_listing_names_every_law_with_its_module():
    rows = {r[0].split()[0]: r for r in registry.describe()}
    assert rows["tss1"][2] == "nodes.controller.skyhook"
    assert "c_sky (required)" in rows["skyhook"][1]
    assert rows["skyhook_on_off"][0] == "skyhook_on_off (= tss1)"
    assert all(r[3] for r in rows.values()), "every law has a one-line docstring"
