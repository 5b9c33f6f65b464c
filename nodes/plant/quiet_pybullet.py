"""``import pybullet`` without its banner.

PyBullet prints ``pybullet build time: <date>`` from C on its first import (on fd 2 or fd 1).
Here fds 1 and 2 point at the null device for the import, C's stdio buffers flushed before
they are given back (a piped stdout buffers the line until exit); Python's streams are
flushed first, and an import error is raised after the descriptors are back. Import ``p``
from here, or this module before anything that imports pybullet (:mod:`.model` does).
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
