"""``import pybullet`` without its banner.

The PyBullet module prints ``pybullet build time: <date>`` from C when it is first imported
(this build: on fd 2, stderr; others print it on fd 1), so every ``suscosim run`` showed it
among its own output (#30 item 8). Here fds 1 and 2 point at the null device for the length
of the import; C's stdio buffers are flushed before the descriptors are given back (when
stdout is a pipe, C buffers the line and would otherwise write it at exit, to the restored
descriptor). Python's own ``sys.stdout`` and ``sys.stderr`` are flushed before, so nothing
of ours is lost; an import error is raised after the descriptors are back. Import ``p`` from
here, or import this module before anything that imports pybullet (the plant models do,
:mod:`.model`).
"""

from __future__ import annotations

import ctypes
import os
import sys
from types import ModuleType


def _quiet_import() -> ModuleType:
    if "pybullet" in sys.modules:
        return sys.modules["pybullet"]
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (AttributeError, ValueError, OSError):  # no stream, or a closed one
            pass
    try:
        saved = [os.dup(1), os.dup(2)]
    except OSError:  # no fd 1 or 2 at all: nothing to hide the banner from
        import pybullet
        return pybullet
    libc = ctypes.CDLL(None)
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        libc.fflush(None)
        os.dup2(devnull, 1)
        os.dup2(devnull, 2)
        import pybullet
        libc.fflush(None)  # the banner, if C buffered it, goes to the null device
    finally:
        for fd, old in zip((1, 2), saved, strict=True):
            os.dup2(old, fd)
            os.close(old)
        os.close(devnull)
    return pybullet


p = _quiet_import()
"""The pybullet module."""
