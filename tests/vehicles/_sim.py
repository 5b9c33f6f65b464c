"""A tiny closed loop for tests: a plant model with a passive damper and point-contact tyres
(what the controller and tyre/road nodes do), stepped in one Python loop."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pybullet as p

from cosim import lower_arm as la
from cosim import scenario as sc
from cosim.channels import CORNERS
from cosim.table import read_table
from nodes.plant import double_wishbone as dw
from nodes.plant import double_wishbone_geometry as geo


def run_closed_loop(model, t_end: float, dt: float, k_t: float, c_s: float,
                    z_g: Callable[[float], np.ndarray]) -> dict[str, np.ndarray]:
    """Return time histories of the state keys and the tyre force ``F_t``."""
    W = model.static_tyre_load()
    out: dict[str, list] = {"t": [], "F_t": []}
    n = int(round(t_end / dt))
    for k in range(n):
        t = k * dt
        st = model.state()
        F_t = np.maximum(0.0, W + k_t * (z_g(t) - st["z_w"]))
        F_d = c_s * (st["v_w"] - st["v_b"])
        model.substep(dt, F_t, F_d)
        st = model.state()
        out["t"].append(t + dt)
        out["F_t"].append(F_t)
        for key, v in st.items():
            out.setdefault(key, []).append(np.array(v, dtype=float))
    return {k: np.array(v) for k, v in out.items()}


def event_run(scenario: Path, folder: Path, *overrides: str) -> SimpleNamespace:
    """An events scenario (scenarios/events/) run by the one-process engine (run.mode =
    "monolithic", the live fatigue node off) into ``folder``; its table as histories per step:
    t [s], F_z (the tyre's F_t), F_x, F_y [N] (n, 4: FL, FR, RL, RR), u [m/s], w_yaw [rad/s],
    pitch, roll [rad], a_x = du/dt - v r, a_y = dv/dt + u r [m/s^2] (body axes, np.gradient
    over the step) and arm[corner][field] (the ``plant/arm_<corner>`` loads)."""
    from orchestrator.runner import resolve, run_scenario

    s = sc.load(scenario, ['run.mode="monolithic"', "fatigue.live=false", *overrides])
    run_scenario(resolve(s, folder), quiet=True)
    tab = read_table(folder / "table.parquet")
    t = tab["t"]
    u, v, r = (tab[f"plant/state/{k}"] for k in ("u", "v", "w_yaw"))

    def four(name: str) -> np.ndarray:
        return np.column_stack([tab[f"{name}[{i}]"] for i in range(4)])

    arm = {c: {k.rsplit("/", 1)[1]: tab[k] for k in tab if k.startswith(f"plant/arm_{c}/")}
           for c in CORNERS}
    return SimpleNamespace(t=t, F_z=four("tyre_road/force/F_t"), F_x=four("tyre_road/force/Fx"),
                           F_y=four("tyre_road/force/Fy"), u=u, w_yaw=r,
                           a_x=np.gradient(u, t) - v * r, a_y=np.gradient(v, t) + u * r,
                           pitch=tab["plant/state/pitch"], roll=tab["plant/state/roll"], arm=arm)


def peak_frequency(x: np.ndarray, dt: float, f_lo: float, f_hi: float) -> float:
    """Frequency [Hz] of the largest spectral peak of ``x`` in [f_lo, f_hi] (Hann window,
    zero padding x8, parabolic interpolation on the log magnitude)."""
    x = np.asarray(x, dtype=float) - np.mean(x)
    n = 8 * len(x)
    X = np.abs(np.fft.rfft(x * np.hanning(len(x)), n=n))
    f = np.fft.rfftfreq(n, dt)
    band = np.where((f >= f_lo) & (f <= f_hi))[0]
    i = band[np.argmax(X[band])]
    a, b, c = np.log(X[i - 1:i + 2])
    return float(f[i] + 0.5 * (a - c) / (a - 2 * b + c) * (f[1] - f[0]))


def _arm_link(m):
    ls = p.getLinkState(m.body, dw.LOWER_ARM, computeLinkVelocity=1, computeForwardKinematics=1,
                        physicsClientId=m.client)
    R = np.array(p.getMatrixFromQuaternion(ls[5])).reshape(3, 3)
    return np.array(ls[0]), np.array(ls[4]), R, np.array(ls[6]), np.array(ls[7])


def big_bump_run(bump_stop: bool, dt: float = 5e-4, height: float = 0.10):
    """The corner over a 1-cos bump ``height`` x 1.0 m at 34 km/h (passive 3800 N s/m on
    v_damper); per substep: F_bs, the arm loads, and the arm's pose and velocities before and
    after."""
    m = dw.DoubleWishboneCorner(dw.DoubleWishboneParams(bump_stop=bump_stop))
    W, v = m.static_tyre_load(), 34.0 / 3.6

    def road(t):
        u = (v * t - 1.0) / 1.0
        return 0.5 * height * (1 - np.cos(2 * np.pi * u)) if 0 <= u <= 1 else 0.0

    out = []
    try:
        for k in range(int(0.5 / dt)):
            st = m.state()
            F_t = np.maximum(0.0, W + 239000.0 * (road(k * dt) - st["z_w"]))
            F_bs = float(m.extra_response()["F_bs"][0])
            before = _arm_link(m)
            m.substep(dt, F_t, 3800.0 * st["v_damper"])
            out.append({"F_bs": F_bs, "L": m.loads()["arm"], "before": before,
                        "after": _arm_link(m), "rel": float(st["z_w"][0] - st["z_b"][0]),
                        "theta": float(st["arm_angle"][0])})
    finally:
        m.close()
    return out, dt


def arm_balance_residuals(rec, dt, with_bump=True):
    """Newton-Euler residuals of the lower arm in world axes: sum F + m g - m a_com [N] and
    sum (r - r_com) x F + M_x e_x - (I alpha + w x I w) [N m]; loads at the pose of t_k."""
    mass = la.MASS_KG
    I = np.diag(geo.BUILTIN.lower_arm_inertia(mass))
    com0, O0, R0, v0, w0 = rec["before"]
    _, _, _, v1, w1 = rec["after"]
    L = rec["L"]
    F_tot = np.array([0.0, 0.0, -mass * 9.81])
    M_tot = R0 @ np.array([L["torsion_bar_mx"], 0.0, 0.0])
    for name, corner_pt in geo.BUILTIN.arm_points.items():
        if name == "bump_stop" and not with_bump:
            continue
        f = R0 @ np.array([L.get(f"{name}_{a}", 0.0) for a in "xyz"])
        r = O0 + R0 @ geo.BUILTIN.to_arm_frame(corner_pt)
        F_tot += f
        M_tot += np.cross(r - com0, f)
    a, alpha = (v1 - v0) / dt, (w1 - w0) / dt
    Iw = R0 @ I @ R0.T
    return F_tot - mass * a, M_tot - (Iw @ alpha + np.cross(w0, Iw @ w0))
