"""The report's fatigue numbers say when the life range over the S-N methods is missing (a
live summary: the live node computes the primary method only) and show it when present."""

from orchestrator.report.fatigue_section import fatigue_numbers


def test_a_live_summary_says_how_to_get_both_s_n_methods() -> None:
    pairs = dict(fatigue_numbers({"source": "live", "min_life_km": 1640.0}))
    assert "suscosim fatigue RUN_DIR" in pairs[
        "life under both S-N methods (Shigley, FKM) at P50 / P97.5"]


def test_a_batch_summary_shows_the_range() -> None:
    fs = {"source": "batch", "min_life_km": 1640.0,
          "sn_methods": {"life_range_km": [1143.0, 3.5e5]}}
    pairs = dict(fatigue_numbers(fs))
    assert pairs["life range over the S-N methods and probabilities [km]"] == [1143.0, 3.5e5]
    assert not any(k.startswith("life under both") for k in pairs)
