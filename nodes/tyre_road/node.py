"""The tyre/road node: road profile under each wheel and the vertical tyre force.

Every step k it waits for the plant's ``state`` (of step k in the sequential exchange, of
step k-1 in the parallel one), evaluates the road height at each contact point of each wheel
(wheel i at distance s_i = v t_k + x_i, x_i its offset from the front axle, on its track) and
publishes ``force``: F_t [N] (absolute, compressive-positive, >= 0), k_t = dF_t/d(z_g - z_w)
[N/m] for the plant's coupling, z_g [m] (road height at the contact centre).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from cosim import channels as ch
from cosim.participant import Participant

from .config import build_road, build_tyre
from .wheel_paths import road_heights


def wheel_geometry(info: dict[str, Any]) -> dict[str, Any]:
    """Static tyre load W [N] and wheel path facts per corner, from the plant's facts."""
    W = np.atleast_1d(np.asarray(info["static_tyre_load"], dtype=float))
    n = W.size
    return {
        "W": W,
        "wheel_x": np.asarray(info.get("wheel_x", [0.0] * n), dtype=float),
        "wheel_track": info.get("wheel_track", [1] * n),
        "corner_names": info.get("corner_names"),
    }


def run(part: Participant, scenario: dict[str, Any]) -> None:
    """Run the tyre/road node until the last step (or until the run is aborted)."""
    run_cfg = scenario["run"]
    h, lag = run_cfg["h"], 0 if run_cfg["exchange"] == "sequential" else 1
    road = build_road(scenario["road"])
    tyre = build_tyre(scenario["tyre"])
    part.output(ch.FORCE)
    state = part.listen(ch.PLANT, ch.STATE, required=("z_w",))
    start = part.handshake(timeout_s=run_cfg["start_timeout_s"])
    geo = wheel_geometry(start["info"][ch.PLANT])
    offsets = np.asarray(tyre.contact_offsets, dtype=float)
    centre = int(np.argmin(np.abs(offsets)))
    n = int(start["n_steps"])
    for k in range(n + 1):
        t = k * h
        msg = part.wait({state: max(k - lag, 0)})[state]
        z_g = road_heights(road, t, geo["wheel_x"], geo["wheel_track"], offsets,
                           geo["corner_names"])
        F_t, k_eff = tyre.force(msg.array("z_w"), z_g, geo["W"])
        part.publish(ch.FORCE, k, t, {"F_t": F_t, "k_t": k_eff, "z_g": z_g[:, centre]})
        part.progress(k, t)
    part.finish(n, n * h)


def static_check(scenario: dict[str, Any]) -> float | None:
    """Preflight: build road and tyre (raises ScenarioError); returns the road's duration [s]."""
    build_tyre(scenario["tyre"])
    return build_road(scenario["road"]).duration_s
