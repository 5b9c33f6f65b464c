"""Native controllers in checkpoints (#29 item 4): Controller.checkpoint_state, as plain data as a
checkpoint file holds it, restored into a freshly built law, continues bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from cosim import plaindata
from nodes.controller.base import BODY_KEYS
from nodes.controller.laws import build_controller

H, N = 0.001, 4
CONFIGS = {
    "passive": {"law": "passive"},
    "skyhook": {"law": "skyhook", "c_sky": 2500.0},
    "skyhook_on_off": {"law": "skyhook_on_off"},
    "skyhook_no_jerk": {"law": "skyhook_no_jerk", "G": 5.0e4},
    "groundhook": {"law": "groundhook", "c_gnd": 1500.0},
    "groundhook_on_off": {"law": "groundhook_on_off"},
    "hybrid": {"law": "hybrid", "alpha": 0.4, "G": 5.0e4},
    "passive_mr": {"law": "passive_mr"},
    "pnr": {"law": "pnr"},
    "tss1": {"law": "tss1"},
    "tss1_pnr": {"law": "tss1_pnr"},
    "tss2": {"law": "tss2"},
    "tss3": {"law": "tss3"},
}


#: the laws whose output depends on their past (a fresh instance differs after 200 steps)
STATEFUL = {"passive_mr", "pnr", "tss1_pnr", "tss2", "tss3"}


def states(steps: int, seed: int):
    rng = np.random.default_rng(seed)
    for _ in range(steps):
        yield {"z_b": rng.normal(0, .01, N), "v_b": rng.normal(0, .3, N),
               "z_w": rng.normal(0, .01, N), "v_w": rng.normal(0, .6, N),
               "v_damper": rng.normal(0, .5, N),
               **{key: rng.normal(0, .1, 1) for key in BODY_KEYS}}


@pytest.mark.parametrize("name", sorted(CONFIGS))
def test_restored_law_continues_bit_for_bit(name):
    parent = build_controller(CONFIGS[name], N, H)
    first = list(states(200, 1))
    for k, s in enumerate(first):
        parent.step(k * H, s)
    saved = plaindata.decode(plaindata.encode(parent.checkpoint_state()))
    after = list(states(200, 2))
    ref = [parent.step((200 + k) * H, s) for k, s in enumerate(after)]
    child = build_controller(CONFIGS[name], N, H)
    child.restore_state(saved, 200 * H, first[-1])
    for k, s in enumerate(after):
        got = child.step((200 + k) * H, s)
        assert got.F_d.tobytes() == ref[k].F_d.tobytes(), (name, k)
        assert got.c_eff.tobytes() == ref[k].c_eff.tobytes(), (name, k)
        assert sorted(got.extra) == sorted(ref[k].extra)
        for key, value in ref[k].extra.items():
            assert np.asarray(got.extra[key]).tobytes() == np.asarray(value).tobytes()
    if name in STATEFUL:  # the restore is what made them equal: a fresh instance differs
        fresh = build_controller(CONFIGS[name], N, H)
        assert [fresh.step((200 + k) * H, s).F_d.tobytes() for k, s in enumerate(after)] != \
            [r.F_d.tobytes() for r in ref]


def test_restore_refuses_another_law():
    saved = build_controller({"law": "tss1"}, N, H).checkpoint_state()
    with pytest.raises(ValueError, match="tss1"):
        build_controller({"law": "tss2"}, N, H).restore_state(saved, 0.0, {})
