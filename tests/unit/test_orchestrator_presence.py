"""A node knows its orchestrator is gone: its liveliness token dropped, or its parent process
ended (cosim.orchestrator_presence)."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

from cosim import orchestrator_presence as op
from cosim.orchestrator_presence import (
    ENV_PARENT_PID,
    ORCHESTRATOR_GONE_S,
    OrchestratorPresence,
    parent_from_env,
    parent_gone,
)


def test_the_parent_pid_is_read_from_the_environment_and_nonsense_is_none() -> None:
    assert parent_from_env({ENV_PARENT_PID: "4321"}) == 4321
    for raw in ("", "x", "1", "0", "-5"):  # init (1) is nobody's orchestrator
        assert parent_from_env({ENV_PARENT_PID: raw}) is None, raw
    assert parent_from_env({}) is None


def test_gone_when_this_process_has_another_parent() -> None:
    assert not parent_gone(os.getppid())
    assert parent_gone(os.getppid() + 100000)  # no such parent
    assert not parent_gone(None)  # a node started elsewhere says nothing


def test_a_child_sees_its_killed_parent_gone() -> None:
    """A middle process starts a grandchild with its own PID in the environment, then is
    SIGKILLed; the grandchild's ``parent_gone`` turns true (it was false while the middle
    process lived)."""
    grandchild = textwrap.dedent("""
        import sys, time
        from cosim.orchestrator_presence import parent_from_env, parent_gone
        pid = parent_from_env()
        print("alive", parent_gone(pid), flush=True)
        deadline = time.monotonic() + 30
        while not parent_gone(pid) and time.monotonic() < deadline:
            time.sleep(0.05)
        print("gone", parent_gone(pid), flush=True)
    """)
    middle = textwrap.dedent(f"""
        import os, subprocess, sys, time
        env = dict(os.environ, {ENV_PARENT_PID}=str(os.getpid()))
        subprocess.Popen([sys.executable, "-c", {grandchild!r}], env=env)
        time.sleep(60)
    """)
    proc = subprocess.Popen([sys.executable, "-c", middle], stdout=subprocess.PIPE, text=True)
    assert proc.stdout is not None
    try:
        assert proc.stdout.readline().split() == ["alive", "False"]
        proc.kill()  # the grandchild's stdout stays open: it still writes to our pipe
        proc.wait(timeout=10)
        assert proc.stdout.readline().split() == ["gone", "True"]
    finally:
        proc.kill()


def test_the_token_counts_once_seen_and_dropped_for_long_enough(monkeypatch) -> None:
    now = [100.0]
    monkeypatch.setattr(op.time, "monotonic", lambda: now[0])
    seen = OrchestratorPresence("r1", "plant", None)
    seen.on_token("k", False)  # a drop before the token was ever seen says nothing
    now[0] += 10 * ORCHESTRATOR_GONE_S
    assert seen.why_gone() is None
    seen.on_token("k", True)
    seen.on_token("k", False)
    now[0] += ORCHESTRATOR_GONE_S / 2
    assert seen.why_gone() is None  # a token re-declared while links reorganise
    seen.on_token("k", True)
    now[0] += 10 * ORCHESTRATOR_GONE_S
    assert seen.why_gone() is None  # back
    seen.on_token("k", False)
    now[0] += ORCHESTRATOR_GONE_S * 1.01
    assert seen.why_gone() == ("plant: the orchestrator of run 'r1' is gone (its liveliness "
                               "token dropped)")


def test_the_parent_process_counts_first() -> None:
    other = os.getppid() + 100000
    presence = OrchestratorPresence("r2", "tyre_road", other)
    assert presence.why_gone() == (f"tyre_road: the orchestrator of run 'r2' is gone (its "
                                   f"process {other}, which started this node, ended)")
    assert OrchestratorPresence("r2", "tyre_road", os.getppid()).why_gone() is None
