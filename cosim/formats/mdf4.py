"""ASAM MDF 4 (``.mf4``) through ``asammdf``: every channel float64 on one time master.

Written: one data group, master ``time`` [s], one channel per column with its name and SI
unit. Read: every non-master channel of every group, all on one time base (else the message
names the channel that differs). A table round-trips exactly.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from cosim.errors import InputFileError
from cosim.safe_open import check_user_file

from .channel_set import ChannelSet

if TYPE_CHECKING:
    from asammdf.blocks import v2_v3_blocks, v4_blocks
    from asammdf.blocks.mdf_common import GroupV3, GroupV4


def write_mdf4(cs: ChannelSet, path: str | Path, comment: str = "suscosim load history"
               ) -> dict[str, Any]:
    """Write ``cs`` as MDF 4.10 to ``path`` (overwritten)."""
    from asammdf import MDF, Signal

    t = np.asarray(cs.t, dtype=np.float64)
    sigs = [Signal(samples=np.asarray(x, dtype=np.float64), timestamps=t, name=name,
                   unit=cs.units.get(name, "")) for name, x in cs.channels.items()]
    mdf = MDF(version="4.10")
    try:
        if sigs:
            mdf.append(sigs, comment=comment)
        mdf.save(str(path), overwrite=True)
    finally:
        mdf.close()
    return {}


def _collect_half_built() -> None:
    """Collect now, silenced, the half-built MDF object asammdf leaves behind a file it
    refuses (its ``__del__`` raises: collected later, inside unrelated code, that can harm)."""
    import gc
    import sys

    hook = sys.unraisablehook
    sys.unraisablehook = lambda _unraisable: None
    try:
        gc.collect()
    finally:
        sys.unraisablehook = hook


def read_mdf4(path: str | Path) -> ChannelSet:
    """Every channel of an MDF 3/4 file on its (common) time master."""
    from asammdf import MDF

    path = str(path)
    check_user_file(path, "mdf")
    failure = ""
    try:
        mdf = MDF(path)
    except Exception as exc:  # asammdf raises many types on a foreign or torn file
        failure = f"{type(exc).__name__}: {exc}"
    if failure:
        _collect_half_built()
        raise InputFileError(path, f"not a readable MDF file ({failure})")
    try:
        t: np.ndarray | None = None
        first = ""
        chans: dict[str, np.ndarray] = {}
        units: dict[str, str] = {}
        # asammdf types groups as list[GroupV3] | list[GroupV4]; either has .channels
        groups: Sequence[GroupV3 | GroupV4] = mdf.groups
        for g, grp in enumerate(groups):
            master = mdf.masters_db.get(g)
            channels: Sequence[v2_v3_blocks.Channel | v4_blocks.Channel] = grp.channels
            for i, ch in enumerate(channels):
                if i == master or not ch.name:
                    continue
                try:
                    sig = mdf.get(group=g, index=i, raw=False)
                except Exception as exc:
                    raise InputFileError(path, f"channel {ch.name!r} cannot be read "
                                               f"({exc})") from None
                x = np.asarray(sig.samples)
                if x.ndim != 1 or x.dtype.kind not in "fiub":
                    continue  # arrays, strings, bus frames: not a load history
                if ch.name in chans:
                    raise InputFileError(path, f"channel name {ch.name!r} appears twice")
                ts = np.asarray(sig.timestamps, dtype=np.float64)
                if t is None:
                    t, first = ts, ch.name
                elif ts.shape != t.shape or not np.array_equal(ts, t):
                    raise InputFileError(path, f"channel {ch.name!r} is not on the time base "
                                               f"of {first!r} (resample the file to one rate)")
                chans[ch.name] = x.astype(np.float64)
                units[ch.name] = str(sig.unit or "")
    finally:
        mdf.close()
    if t is None:
        raise InputFileError(path, "no numeric channel in the file")
    return ChannelSet(t=t, channels=chans, units=units)
