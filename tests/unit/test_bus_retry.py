"""A session retries an endpoint it could not reach soon (cosim.bus.CONNECT_RETRY)."""

from __future__ import annotations

import json
import time

from cosim.bus import CONNECT_RETRY, ZenohBus, free_loopback_endpoint, zenoh_config
from cosim.zenoh_options import apply_mode


def _retry(conf) -> dict:
    return json.loads(conf.get_json("connect/retry"))


def test_the_retry_is_ours_unless_a_config_file_gives_its_own(tmp_path) -> None:
    assert _retry(zenoh_config(connect=["tcp/127.0.0.1:7447"])) == CONNECT_RETRY
    own = {"period_init_ms": 2000, "period_max_ms": 8000, "period_increase_factor": 2.0}
    path = tmp_path / "z.json5"
    path.write_text(json.dumps({"connect": {"retry": own}}))
    assert _retry(zenoh_config(config_file=str(path))) == own
    assert _retry(apply_mode(zenoh_config(), "client")) == CONNECT_RETRY


def test_a_session_opened_before_its_peer_listens_links_soon_after() -> None:
    """Zenoh's own retry (1 s, doubling to 4 s) linked 3.2 s after the listener came up when
    it came 3.3 s after the session opened; ours must link within a retry period or two."""
    endpoint = free_loopback_endpoint()
    early = ZenohBus(zenoh_config(connect=[endpoint]))
    try:
        assert not early.wait_linked(timeout=0.2)  # nobody listens yet
        time.sleep(3.3)  # past Zenoh's own 1 s + 2 s retries, before its 4 s one
        late = ZenohBus(zenoh_config(listen=[endpoint]))
        try:
            # within 2 s: after 3.5 s the own retry would only try again at 7.5 s
            assert early.wait_linked(timeout=2.0)
        finally:
            late.close()
    finally:
        early.close()
