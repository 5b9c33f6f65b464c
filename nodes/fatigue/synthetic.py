"""Synthetic lower-arm load histories for tests and benchmarks (not a road model).

Ball-joint forces of a front MPV corner on a rough (pavé-like) road: a static vertical load
plus band-limited random parts (0.5-30 Hz), and the damper/spring force at the arm mount that
balances the vertical ball-joint load about the pivot axis (lever ratio y_bj / y_dm), so that
the bush reactions stay moderate; the bush forces and the torsion-spring moment close the
arm's static balance (`balance_at_pivot`). Newtons, arm frame (see `cosim.lower_arm`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.signal import butter, sosfiltfilt

from cosim import lower_arm as geo


def _band_noise(rng: np.random.Generator, n: int, fs: float, lo: float, hi: float) -> np.ndarray:
    sos = butter(4, [lo, hi], btype="band", fs=fs, output="sos")
    x = sosfiltfilt(sos, rng.normal(size=n + 2000))[1000:-1000]
    return x / x.std()


def pave_like_loads(duration_s: float = 37.0, fs: float = 500.0, seed: int = 0,
                    static_n: float = 4000.0, rms_n: float = 1500.0) -> tuple[np.ndarray, dict]:
    """(t, {channel: force N}) with channels ``plant/arm/<point>_<axis>``."""
    rng = np.random.default_rng(seed)
    n = int(round(duration_s * fs))
    t = np.arange(n) / fs
    fz = static_n + rms_n * _band_noise(rng, n, fs, 0.5, 30.0)
    fx = 0.25 * rms_n * _band_noise(rng, n, fs, 0.5, 20.0)
    fy = -0.1 * static_n + 0.3 * rms_n * _band_noise(rng, n, fs, 0.5, 20.0)
    lever = geo.BALL_JOINT[1] / geo.DAMPER_MOUNT[1]
    loads = {
        "plant/arm/ball_joint_x": fx,
        "plant/arm/ball_joint_y": fy,
        "plant/arm/ball_joint_z": fz,
        "plant/arm/damper_mount_x": np.zeros(n),
        "plant/arm/damper_mount_y": np.zeros(n),
        "plant/arm/damper_mount_z": -lever * fz,
    }
    loads.update(balance_at_pivot(loads))
    return t, loads


def balance_at_pivot(loads: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Bush forces and torsion-spring moment [N, N m] that put the arm in static balance with
    the given loads (channels ``plant/arm/<point>_<axis>``): the bushes (on the pivot axis x at
    x_f, x_r) take the force and the moments about y and z, sharing the axial force equally;
    the torsion spring takes the moment about x."""
    # sums of force [N] and moment [N m] components: 0.0, then arrays once a load is added
    F: list[Any] = [0.0, 0.0, 0.0]
    M: list[Any] = [0.0, 0.0, 0.0]
    for name, p in geo.HARDPOINTS.items():
        f = [np.asarray(loads.get(f"plant/arm/{name}_{a}", 0.0)) for a in "xyz"]
        F = [F[k] + f[k] for k in range(3)]
        M = [M[0] + p[1] * f[2] - p[2] * f[1], M[1] + p[2] * f[0] - p[0] * f[2],
             M[2] + p[0] * f[1] - p[1] * f[0]]
    xf, xr = float(geo.BUSH_FRONT[0]), float(geo.BUSH_REAR[0])
    # bush z: Fzf + Fzr = -Fz, -(xf Fzf + xr Fzr) = -My ; bush y: Fyf + Fyr = -Fy,
    # xf Fyf + xr Fyr = -Mz
    fzf = (M[1] + xr * F[2]) / (xf - xr)
    fyf = (-M[2] + xr * F[1]) / (xf - xr)
    return {
        "plant/arm/bush_front_x": -0.5 * F[0], "plant/arm/bush_rear_x": -0.5 * F[0],
        "plant/arm/bush_front_y": fyf, "plant/arm/bush_rear_y": -F[1] - fyf,
        "plant/arm/bush_front_z": fzf, "plant/arm/bush_rear_z": -F[2] - fzf,
        "plant/arm/torsion_bar_mx": -M[0],
    }
