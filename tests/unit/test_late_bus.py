"""LateBus: a client session opened once its endpoint answers, with the subscriptions asked
of it before then (what a tap or scope started before its run uses)."""

from __future__ import annotations

import threading
import time

from cosim.bus import ZenohBus, free_loopback_endpoint, zenoh_config
from cosim.zenoh_options import LateBus, open_bus


def test_a_subscription_made_before_the_endpoint_answers_hears_it_after() -> None:
    endpoint = free_loopback_endpoint()
    late = LateBus(lambda ms: open_bus([endpoint], None, "client", connect_timeout_ms=ms))
    heard: list[bytes] = []
    got = threading.Event()

    def on(_key: str, raw: bytes) -> None:
        heard.append(raw)
        got.set()

    late.subscribe("late/**", on)
    try:
        assert late.query("late/q") is None and late.query_all("late/q") == []
        assert not late.linked()
        time.sleep(1.5)  # more than one attempt failed meanwhile
        peer = ZenohBus(zenoh_config(listen=[endpoint]))
        try:
            peer.serve("late/q", lambda: b"answer")
            deadline = time.monotonic() + 30
            while not late.linked():
                assert time.monotonic() < deadline, "the late client never linked"
                time.sleep(0.05)
            pub = peer.publisher("late/x")
            while not got.is_set():  # until its subscription has reached the peer
                assert time.monotonic() < deadline, "the subscription never arrived"
                pub(b"hello")
                got.wait(0.1)
            assert heard[0] == b"hello"
            assert late.query("late/q", timeout=5.0) == b"answer"
        finally:
            peer.close()
    finally:
        late.close()


def test_closing_a_bus_that_never_opened_ends_its_thread() -> None:
    late = LateBus(lambda ms: open_bus([free_loopback_endpoint()], None, "client",
                                       connect_timeout_ms=ms))
    late.subscribe("x/**", lambda key, raw: None)
    late.close()
    assert not late._thread.is_alive()
    assert not late.linked()
