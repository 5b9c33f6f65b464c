"""Relative file paths of a scenario made absolute against its folder, lists included
(``fatigue.parts``), and the keys that are no path left alone."""

from pathlib import Path

from cosim import scenario as sc
from orchestrator.sweep.spec import _absolute_paths


def test_a_list_of_part_files_is_made_absolute_and_a_shipped_name_stays_a_name() -> None:
    folder = Path("/data/study")
    s = {"fatigue": {"influence": "builtin", "parts": ["upper_arm", "parts/knuckle.toml",
                                                      "/abs/hub.toml"]},
         "road": {"path": "roads/pave.csv"}}
    sc.absolute_paths(s, folder)
    assert s["fatigue"]["influence"] == "builtin"
    assert s["fatigue"]["parts"] == ["upper_arm", "/data/study/parts/knuckle.toml",
                                     "/abs/hub.toml"]
    assert s["road"]["path"] == "/data/study/roads/pave.csv"


def test_sweep_overrides_use_the_same_rule() -> None:
    out = _absolute_paths({"fatigue.parts": ["k.toml", "upper_arm"],
                           "fatigue": {"influence": "builtin"}}, Path("/s"))
    assert out == {"fatigue.parts": ["/s/k.toml", "upper_arm"],
                   "fatigue": {"influence": "builtin"}}
