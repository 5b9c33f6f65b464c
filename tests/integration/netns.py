"""Three Linux network namespaces standing in for three machines (root only).

::

    [plant ns B] 10.77.1.2 --veth-- 10.77.1.1 [router ns A] 10.77.2.1 --veth-- 10.77.2.2 [main ns C]

Namespace A holds the Zenoh router; B the plant node; C the orchestrator and the other nodes.
A does not forward IP packets (a fresh namespace has ``ip_forward = 0``), so B and C reach each
other only through the router, as two machines on two networks would. Every name carries a
random tag, so several topologies (or test runs) never collide. Used by
``tests/integration/test_netns.py`` and ``python -m bench transport``.
"""

from __future__ import annotations

import os
import secrets
import shutil
import signal
import subprocess
import time

ROUTER, PLANT, MAIN = "router", "plant", "main"
ADDR = {PLANT: "10.77.1.2", MAIN: "10.77.2.2"}
"""Address of each outer namespace; the router's side of its link ends in .1."""
ROUTER_ADDR = {PLANT: "10.77.1.1", MAIN: "10.77.2.1"}
"""The router's address as seen from each outer namespace."""


def unavailable() -> str | None:
    """Why namespaces cannot be made here (a skip reason), or None when they can."""
    if os.geteuid() != 0:
        return "needs root to create Linux network namespaces (not root)"
    if shutil.which("ip") is None:
        return "needs the 'ip' command (iproute2) to create network namespaces"
    probe = f"scprobe{secrets.token_hex(3)}"
    res = subprocess.run(["ip", "netns", "add", probe], capture_output=True, text=True)
    if res.returncode != 0:
        return f"'ip netns add' failed here: {res.stderr.strip() or res.returncode}"
    subprocess.run(["ip", "netns", "del", probe], capture_output=True)
    return None


def _ip(*args: str) -> None:
    res = subprocess.run(["ip", *args], capture_output=True, text=True)
    if res.returncode != 0:
        raise RuntimeError(f"ip {' '.join(args)}: {res.stderr.strip()}")


class Topology:
    """The three namespaces and their two links; :meth:`close` removes everything."""

    def __init__(self) -> None:
        tag = secrets.token_hex(3)
        self.ns = {ROUTER: f"sc{tag}r", PLANT: f"sc{tag}p", MAIN: f"sc{tag}m"}
        # veth ends: (end in the router namespace, end in the outer namespace)
        self.links = {PLANT: (f"sc{tag}rp", f"sc{tag}pr"), MAIN: (f"sc{tag}rm", f"sc{tag}mr")}
        self._made: list[str] = []
        try:
            for ns in self.ns.values():
                _ip("netns", "add", ns)
                self._made.append(ns)
                _ip("-n", ns, "link", "set", "lo", "up")
            for outer in (PLANT, MAIN):
                r_end, o_end = self.links[outer]
                _ip("-n", self.ns[ROUTER], "link", "add", r_end, "type", "veth",
                    "peer", "name", o_end, "netns", self.ns[outer])
                _ip("-n", self.ns[ROUTER], "addr", "add", f"{ROUTER_ADDR[outer]}/24",
                    "dev", r_end)
                _ip("-n", self.ns[outer], "addr", "add", f"{ADDR[outer]}/24", "dev", o_end)
                _ip("-n", self.ns[ROUTER], "link", "set", r_end, "up")
                _ip("-n", self.ns[outer], "link", "set", o_end, "up")
        except BaseException:
            self.close()
            raise

    def cmd(self, where: str, argv: list[str]) -> list[str]:
        """``argv`` run inside namespace ``where`` (router, plant or main)."""
        return ["ip", "netns", "exec", self.ns[where], *argv]

    def cut(self, outer: str) -> None:
        """Partition ``outer`` (plant or main): both ends of its link go down."""
        r_end, o_end = self.links[outer]
        _ip("-n", self.ns[ROUTER], "link", "set", r_end, "down")
        _ip("-n", self.ns[outer], "link", "set", o_end, "down")

    def close(self) -> None:
        """Stop whatever still runs in the namespaces (our processes), then delete them."""
        for ns in self._made:
            res = subprocess.run(["ip", "netns", "pids", ns], capture_output=True, text=True)
            for pid in (int(p) for p in res.stdout.split()):
                try:
                    os.kill(pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
        time.sleep(0.1)
        for ns in self._made:
            subprocess.run(["ip", "netns", "del", ns], capture_output=True)
        self._made.clear()
