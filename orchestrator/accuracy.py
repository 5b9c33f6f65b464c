"""Accuracy of a co-simulation against the reference, as Table 3.3 of the thesis measures it:
Eq. 3.5, %diff = (Peak_cosim - Peak_reference) / Peak_reference x 100, of the maximum and the
minimum of each response (the reference's on a fine grid: the continuous solution's true peak).
"""

from __future__ import annotations

from typing import Any

from cosim.table import Table

TABLE_3_3_SIGNALS = {
    "body displacement": "plant/state/z_b", "wheel displacement": "plant/state/z_w",
    "wheel acceleration": "plant/response/a_w", "tyre force": "plant/response/F_t",
}


def peak_errors(cosim: Table, reference: Table, signals: dict[str, str] | None = None,
                t_from: float = 0.0) -> dict[str, dict[str, float]]:
    """Per signal: % error of the max and of the min (a valley only) after ``t_from`` [s]."""

    out: dict[str, dict[str, float]] = {}
    for label, col in (signals or TABLE_3_3_SIGNALS).items():
        a = cosim[col][cosim["t"] >= t_from]
        r = reference[col][reference["t"] >= t_from]
        out[label] = {"max": 100.0 * (a.max() - r.max()) / abs(r.max())}
        if abs(r.min()) > 0.01 * abs(r.max()):  # a real valley, not the initial rest value
            out[label]["min"] = 100.0 * (a.min() - r.min()) / abs(r.min())
    return out


def worst(errors: dict[str, dict[str, Any]]) -> float:
    """The largest |% error| over signals and max/min."""
    return max(abs(v) for e in errors.values() for v in e.values())
