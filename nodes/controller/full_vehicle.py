"""Full-vehicle pitch-and-roll two-state controller, TSS1 PnR (thesis Sec 5.4.4, Eqs 5.4-5.12,
Table 5.2; after Nell & Steyn [20]).

Each step, for the 16 soft/hard combinations MP1..MP16 of the four dampers (FL, FR, RL, RR),
the corner forces ``F_i = c_i * v_rel_i`` are formed and the combination with the minimum
product (MP) of the damper moment and the body angular acceleration is chosen:

* if ``|theta''| > |phi''|`` (pitch dominates, Eq 5.6/5.7):
  ``P_n = (F_FL + F_FR - F_RL - F_RR)_n * theta''``
* else (Eq 5.8): ``P_n = (F_FL + F_RL - F_FR - F_RR)_n * phi''``

with ``theta''`` the nose-**up** pitch acceleration (Eq 5.4: ``(z_FL'' - z_RL'')/wheelbase``)
and ``phi''`` the left-**up** roll acceleration (Eq 5.5: ``(z_FL'' - z_FR'')/track``), rad/s².
``F_i`` is the force on the body, upward positive, so the front-minus-rear sum is a nose-up
moment (per unit lever arm) and the minimum product is the combination whose damper moment
most *opposes* the angular acceleration — the intent of [20]. (With the thesis's
``d_i = C v_rel`` as a force that acts on the body with the opposite sign, the same minimum
would aid the motion; see docs/control.md.)

In ISO 8855 (x forward, y left, z up) the pitch rate ``w_pitch`` is about +y (nose down
positive) and the roll rate ``w_roll`` about +x (left side up positive), hence
``theta'' = -d(w_pitch)/dt`` and ``phi'' = +d(w_roll)/dt``.
"""

from __future__ import annotations

import numpy as np

#: (16, 4) bool: row n-1 is MPn, True = hard, columns FL, FR, RL, RR (binary n-1, FL = MSB).
COMBINATIONS = np.array([[(n >> (3 - i)) & 1 for i in range(4)] for n in range(16)], dtype=bool)


def combination_label(index: int) -> str:
    """Table 5.2 name of combination ``index`` (0-based), e.g. 8 -> ``"MP9 HSSS"``."""
    pattern = "".join("H" if h else "S" for h in COMBINATIONS[index])
    return f"MP{index + 1} {pattern}"


def pnr_products(v_rel: np.ndarray, c_soft: float, c_hard: float, theta_dd: float,
                 phi_dd: float) -> tuple[np.ndarray, np.ndarray, bool]:
    """(forces (16, 4) on the body in N, products (16,) in N·rad/s², pitch branch) of all 16
    combinations, from ``v_rel`` (m/s, FL, FR, RL, RR), ``c_soft``/``c_hard`` (N·s/m, Table
    5.2: 1500 / 2368), ``theta_dd`` nose-up and ``phi_dd`` left-up (rad/s²)."""
    v = np.asarray(v_rel, dtype=float).reshape(4)
    forces = np.where(COMBINATIONS, c_hard, c_soft) * v
    fl, fr, rl, rr = forces.T
    pitch_branch = abs(theta_dd) > abs(phi_dd)
    products = (fl + fr - rl - rr) * theta_dd if pitch_branch else (fl + rl - fr - rr) * phi_dd
    return forces, products, pitch_branch


def pnr_select(v_rel: np.ndarray, c_soft: float, c_hard: float, theta_dd: float,
               phi_dd: float) -> tuple[int, np.ndarray, np.ndarray]:
    """(index n of MP(n+1), forces (4,) in N, coefficients (4,) in N·s/m) of the
    minimum-product combination (ties: the lowest MP, so no angular acceleration: all soft)."""
    forces, products, _ = pnr_products(v_rel, c_soft, c_hard, theta_dd, phi_dd)
    n = int(np.argmin(products))
    c = np.where(COMBINATIONS[n], c_hard, c_soft).astype(float)
    return n, forces[n].copy(), c
