"""Issue #30 item 13: a run id live through a router must be refused to a second run.

A peer session's first liveliness query through a router answers ``[]`` at once, before the
router has told it of the tokens it knows (4 of 5 first queries on an idle 2-core machine):
one query let a second run with the id of a running one start. :func:`check_run_id_free`
now looks over a settle window (:data:`cosim.run_lock.SETTLE_S`)."""

from __future__ import annotations

import time

import pytest

from cosim import keys
from cosim.bus import ZenohBus, free_loopback_endpoint, zenoh_config
from cosim.run_lock import RunIdInUseError, check_run_id_free
from tests.conftest import CH3_STEP, popen_suscosim, suscosim


@pytest.fixture
def router():
    ep = free_loopback_endpoint()
    proc = popen_suscosim("router", "--listen", ep)
    try:
        bus = None
        for _ in range(100):  # up once a client session opens against it
            assert proc.poll() is None, proc.stderr.read()
            try:
                bus = ZenohBus(zenoh_config([ep], default_mode="client"))
                break
            except Exception:
                time.sleep(0.1)
        assert bus is not None
        bus.close()
        yield ep
    finally:
        proc.terminate()
        proc.wait(timeout=10)


def _orchestrator_session(ep: str) -> ZenohBus:
    """A session as ``suscosim run --connect`` opens it: a peer listening on loopback."""
    return ZenohBus(zenoh_config([ep], [free_loopback_endpoint()], default_mode="peer"))


def test_a_token_live_through_a_router_is_seen_by_a_session_just_opened(router) -> None:
    first = _orchestrator_session(router)
    first.token(keys.key("dup", keys.ORCHESTRATOR, keys.ALIVE))  # the running run
    try:
        time.sleep(0.5)
        for _ in range(5):  # a single query missed it 4 times in 5
            second = _orchestrator_session(router)
            try:
                with pytest.raises(RunIdInUseError, match="orchestrator"):
                    check_run_id_free(second, "dup", [])
                check_run_id_free(second, "other-id", [], settle_s=0.3)  # not refused
            finally:
                second.close()
    finally:
        first.close()


def test_a_second_run_with_the_id_of_a_running_one_is_refused(router, tmp_path,
                                                               monkeypatch) -> None:
    monkeypatch.setenv("SUSCOSIM_KEY", "run-id-router-test")
    first = popen_suscosim("run", str(CH3_STEP), "--quiet", "--connect", router,
                           "--out", str(tmp_path / "a"), "--set", 'run.id="dup-run"',
                           "--set", "run.t_end=60")
    try:
        watcher = _orchestrator_session(router)
        try:  # wait until the first run's orchestrator is on the bus
            for _ in range(300):
                assert first.poll() is None, first.stderr.read()
                if watcher.alive(keys.key("dup-run", keys.ORCHESTRATOR, keys.ALIVE)):
                    break
                time.sleep(0.1)
            else:
                pytest.fail("the first run never declared itself")
        finally:
            watcher.close()
        res = suscosim("run", str(CH3_STEP), "--quiet", "--connect", router,
                       "--out", str(tmp_path / "b"), "--set", 'run.id="dup-run"',
                       "--set", "run.t_end=0.05")
        assert res.returncode == 2, res.stdout + res.stderr
        assert "run id 'dup-run' is already live on the bus" in res.stderr
        assert first.poll() is None  # the first run goes on
    finally:
        first.terminate()
        first.wait(timeout=30)
