"""Which signals the report shows: units, per-corner columns, panels, arm loads, PSDs."""

from __future__ import annotations

import re
from collections.abc import Sequence

import numpy as np

from cosim.channels import CORNERS

PSD_F_MAX_HZ = 50.0  # [Hz] upper end of the PSD plots (or Nyquist, if lower)


UNITS = {"z": "m", "v": "m/s", "a": "m/s²", "F": "N", "k_t": "N/m", "c_eff": "N·s/m",
         "heave": "m", "pitch": "rad", "roll": "rad", "v_heave": "m/s", "w_pitch": "rad/s",
         "w_roll": "rad/s", "arm_angle": "rad", "I": "A", "state": "-"}


def unit_of(column: str) -> str:
    parts = column.split("/")
    fld = re.sub(r"\[\d+\]$", "", parts[-1])
    if len(parts) >= 2 and parts[-2] == "arm":
        return "N·m" if fld.rsplit("_", 1)[-1].startswith("m") else "N"
    return UNITS[fld] if fld in UNITS else UNITS.get(fld.split("_", 1)[0], "")


def corner_cols(table: dict[str, np.ndarray], base: str) -> list[tuple[str, np.ndarray]]:
    from nodes.recorder.ride_metrics import columns

    out = columns(table, base)
    if len(out) == 4:
        return [(CORNERS[i], x) for i, (_lab, x) in enumerate(out)]
    return [(lab.strip("[]"), x) for lab, x in out]


def first_present(table: dict[str, np.ndarray], bases: Sequence[str]) -> tuple[str, list]:
    for b in bases:
        cols = corner_cols(table, b)
        if cols:
            return b, cols
    return "", []


BODY_ACC = ("plant/response/a_b",)
TYRE_FORCE = ("tyre_road/force/F_t", "plant/response/F_t")
DAMPER_FORCE = ("controller/force/F_d", "plant/response/F_d")


def corner_label(name: str, corner: str) -> str:
    return f"{name} {corner}".strip()


def time_history_panels(table: dict[str, np.ndarray]) -> tuple[list[tuple], list[str]]:
    """The panels ``[(title, unit, [(label, y)])]`` a table allows, and the missing titles."""
    panels: list[tuple] = []
    missing: list[str] = []

    def add(title: str, unit: str, lines: list[tuple[str, np.ndarray]]) -> None:
        if lines:
            panels.append((title, unit, lines))
        else:
            missing.append(title)

    disp = [(corner_label(name, c), 1e3 * x) for base, name in (
        ("plant/state/z_b", "body z_b"), ("plant/state/z_w", "wheel z_w"),
        ("tyre_road/force/z_g", "road z_g")) for c, x in corner_cols(table, base)]
    add("Body and wheel displacement", "mm", disp)
    add("Body acceleration", "m/s²",
        [(corner_label("a_b", c), x) for c, x in corner_cols(table, "plant/response/a_b")])
    add("Wheel acceleration", "m/s²",
        [(corner_label("a_w", c), x) for c, x in corner_cols(table, "plant/response/a_w")])
    travel = [(corner_label("z_w − z_b", c), 1e3 * (w - b)) for (c, b), (_c, w) in
              zip(corner_cols(table, "plant/state/z_b"), corner_cols(table, "plant/state/z_w"),
                  strict=False)]
    travel += [(corner_label("damper compression", c), 1e3 * x)
               for c, x in corner_cols(table, "plant/state/z_damper")]
    add("Suspension travel (compression +)", "mm", travel)
    base, cols = first_present(table, TYRE_FORCE)
    add("Tyre force", "N", [(corner_label("F_t", c), x) for c, x in cols])
    base, cols = first_present(table, DAMPER_FORCE)
    add("Damper force", "N", [(corner_label("F_d", c), x) for c, x in cols])
    return panels, missing


def welch_psd(x: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """One-sided Welch PSD (Hann, ~8 averages, mean removed): (f [Hz], P [unit²/Hz])."""
    from scipy.signal import welch

    n = x.size
    nperseg = int(min(n, max(256, n // 4)))
    return welch(x, fs=fs, nperseg=nperseg, detrend="constant")


def sample_rate(t: np.ndarray) -> float | None:
    from nodes.recorder.ride_metrics import sample_rate as _sr

    try:
        return _sr(t)
    except ValueError:
        return None


def arm_groups(table: dict[str, np.ndarray]) -> dict[str, list[tuple[str, np.ndarray]]]:
    groups: dict[str, list[tuple[str, np.ndarray]]] = {}
    for name in sorted(table):
        if not name.startswith("plant/arm/"):
            continue
        fld = name[len("plant/arm/"):]
        point, _, axis = fld.rpartition("_")
        groups.setdefault(point or fld, []).append((axis or fld, table[name]))
    return groups
