"""ZenohBus.close returns only once its callbacks have delivered their last sample.

Zenoh runs a Python callback in a Python thread of its own. A tap that closed its session
while that thread still held samples, then exited, aborted at interpreter exit ("FATAL:
exception not rethrown", SIGABRT; CI, and 3 of 89 taps of a live run): the thread, woken in
Zenoh's frames during finalization, was ended by a forced unwind that those frames stop.
"""

from __future__ import annotations

import threading
import time

from cosim.bus import ZenohBus, free_loopback_endpoint, zenoh_config


def _pair() -> tuple[ZenohBus, ZenohBus]:
    endpoint = free_loopback_endpoint()
    server = ZenohBus(zenoh_config(listen=[endpoint], gossip=False))
    client = ZenohBus(zenoh_config(connect=[endpoint], gossip=False))
    return server, client


def test_close_waits_for_a_slow_callback_to_deliver_what_it_holds() -> None:
    server, client = _pair()
    delivered: list[int] = []
    busy = threading.Event()
    first = threading.Event()

    def slow(_key: str, raw: bytes) -> None:
        busy.set()
        first.set()
        time.sleep(0.02)  # 20 ms per sample: 50 samples hold the thread ~1 s
        delivered.append(int(raw))
        busy.clear()

    try:
        client.subscribe("t/close/x", slow)
        put = server.publisher("t/close/x")
        deadline = time.monotonic() + 10.0
        while not first.is_set() and time.monotonic() < deadline:
            put(b"-1")  # until the subscription has reached the server
            time.sleep(0.01)
        assert first.is_set(), "the subscriber never got a sample"
        for i in range(50):
            put(str(i).encode())
        time.sleep(0.1)  # the samples reach the client; its callback thread has a backlog
        assert 49 not in delivered  # still delivering when close is called
    finally:
        client.close()
        at_close = len(delivered)
        running = busy.is_set()
        server.close()
    time.sleep(0.3)
    # Nothing is delivered after close returned, and no callback was midway.
    assert not running
    assert len(delivered) == at_close
