"""A local node knows its orchestrator's process is gone (cosim.local_parent)."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

from cosim.local_parent import ENV_PARENT_PID, parent_from_env, parent_gone


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
        from cosim.local_parent import parent_from_env, parent_gone
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
