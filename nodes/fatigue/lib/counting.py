"""Rainflow cycle counting of many stress histories at once, sample by sample (streaming).

The counter is the four-point rainflow rule (Matsuishi & Endo; ASTM E1049-85 §5.4.4 in its
stack form): with the four most recent turning points ``a, b, c, d`` of a history, the range
``b-c`` is a closed cycle when ``|b - c| <= |a - b|`` and ``|b - c| <= |c - d|``; ``b`` and ``c``
are removed and the test is repeated. What never closes is the *residue*.

Residue handling (the only place the four-point rule and ASTM's three-point rule differ):

* ``"half_cycles"``: every range between consecutive residue points is half a cycle. Full
  plus half cycles are then exactly ASTM E1049-85's rainflow count (the ``rainflow`` package's
  ``count_cycles``), which the tests check.
* ``"repeated"``: the history is one pass of a track driven again and again; the residue is
  run through the counter once more, which closes the cycles that span the repeat (the
  "start at the highest peak" rearrangement of ASTM §5.4.4.1). Life in repeats of the track
  is then exact for the periodic history.

Because the state (the stack of unclosed turning points per history) is kept between calls,
feeding a history in blocks of any size gives exactly the same cycles as feeding it at once.

**Compiled:** the rule runs history by history in compiled code (:func:`_rainflow_packed`,
numba; :meth:`StreamingRainflow.feed_packed` takes a block's possible turning points packed,
:meth:`StreamingRainflow.feed` every sample): comparisons and copies only, each history's
cycles in the order they close (a node's damage sums its own cycles in order). numba is a
dependency: the kernel is the one implementation (the lock-step numpy counter over all
histories at once is the test oracle, ``tests/fatigue/oracle_turning_eq.py``).
The kernels are compiled when first needed or ahead (:func:`nodes.fatigue.worker.warm_up`,
which the worker's influence loading calls: the live node does it before it says ready), not
at import (numba's import and start cost ~1 s, and every run's preflight imports this).
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass

import numpy as np

COMPILE_S: dict[str, float] = {}
"""Per module, the seconds its kernels took to compile or to load from numba's disk cache."""
_COMPILE_LOCK = threading.Lock()


def compile_kernels(g: dict, kernels: tuple[tuple[str, str], ...],
                    inline: tuple[str, ...] = ()) -> None:
    """Replace the pure-Python kernels ``kernels`` ((name, numba signature), callees first)
    of the module whose globals are ``g`` by numba functions compiled now: explicit
    signatures, ``cache=True`` (in ``__pycache__``, or numba's user cache where that is
    read-only), no fastmath (IEEE operations in the order written); the helpers ``inline``
    (names in ``g``) are inlined into them (``inline="always"``). Once per module, any
    thread. numba is a dependency: one that does not import is an error."""
    name = g["__name__"]
    if name in COMPILE_S:
        return
    with _COMPILE_LOCK:
        if name in COMPILE_S:
            return
        t0 = time.perf_counter()
        try:
            import numba
        except Exception as exc:  # a broken install: say so
            raise RuntimeError(f"numba does not import ({exc}); the fatigue kernels need it "
                               "(a dependency: pip install numba)") from exc
        for fn in inline:
            g[fn] = numba.njit(inline="always")(getattr(g[fn], "py_func", g[fn]))
        for fn, sig in kernels:
            g[fn] = numba.njit(sig, cache=True, error_model="numpy", nogil=True)(g[fn])
        COMPILE_S[name] = time.perf_counter() - t0

RESIDUE_MODES = ("half_cycles", "repeated")
FEED_ROWS = 4096
"""Rows :meth:`StreamingRainflow.feed` passes to the kernel at a time (the stack needs room
for them: 32 kB a history)."""


@dataclass
class Cycles:
    """Counted cycles of many histories, one entry per cycle: ``series`` the history (FE
    node), ``s1``, ``s2`` its two turning points (Pa for stresses; range |s1 - s2|, mean
    (s1 + s2)/2), ``count`` 1.0 for a full cycle, 0.5 for a half cycle."""

    series: np.ndarray
    s1: np.ndarray
    s2: np.ndarray
    count: np.ndarray

    @property
    def range(self) -> np.ndarray:
        return np.abs(self.s1 - self.s2)

    @property
    def mean(self) -> np.ndarray:
        return 0.5 * (self.s1 + self.s2)

    def __len__(self) -> int:
        return int(self.series.size)

    @staticmethod
    def empty() -> Cycles:
        z = np.zeros(0)
        return Cycles(np.zeros(0, dtype=np.int64), z, z.copy(), z.copy())

    @staticmethod
    def concat(parts: list[Cycles]) -> Cycles:
        parts = [p for p in parts if len(p)]
        if not parts:
            return Cycles.empty()
        return Cycles(
            np.concatenate([p.series for p in parts]),
            np.concatenate([p.s1 for p in parts]),
            np.concatenate([p.s2 for p in parts]),
            np.concatenate([p.count for p in parts]),
        )


class StreamingRainflow:
    """Four-point rainflow counter over ``n_series`` histories advanced together.

    Use `feed` with consecutive blocks (n_samples, n_series); closed full cycles are returned
    by `feed` (and are never returned again). `residue_cycles` gives the cycles of the
    residue without changing the state, so a provisional result can be taken mid-stream.
    """

    def __init__(self, n_series: int, capacity: int = 64) -> None:
        self.n = int(n_series)
        self._cap = int(capacity)
        self._stack = np.zeros((self.n, self._cap))
        self._depth = np.zeros(self.n, dtype=np.int64)
        self._last: np.ndarray | None = None

    # -- state ---------------------------------------------------------------------------
    @property
    def depth(self) -> np.ndarray:
        """Number of residue points per history."""
        return self._depth.copy()

    @property
    def last(self) -> np.ndarray | None:
        """The last sample fed of each history (None before the first feed)."""
        return self._last

    def residue_variation(self) -> np.ndarray:
        """Total variation of each history's residue, Σ |r_(j+1) - r_j| (Pa)."""
        m = int(self._depth.max()) if self.n else 0
        if m < 2:
            return np.zeros(self.n)
        d = np.abs(np.diff(self._stack[:, :m], axis=1))
        valid = np.arange(m - 1)[None, :] < (self._depth - 1)[:, None]
        return np.where(valid, d, 0.0).sum(axis=1)

    def residue(self, i: int) -> np.ndarray:
        """Turning points not yet closed into cycles, history ``i``."""
        return self._stack[i, : self._depth[i]].copy()

    def copy(self) -> StreamingRainflow:
        other = StreamingRainflow.__new__(StreamingRainflow)
        other.n, other._cap = self.n, self._cap
        other._stack = self._stack.copy()
        other._depth = self._depth.copy()
        other._last = None if self._last is None else self._last.copy()
        return other

    def take(self, idx: np.ndarray) -> StreamingRainflow:
        """A counter of the histories ``idx`` only (their states copied, in that order)."""
        idx = np.asarray(idx, dtype=np.int64)
        other = StreamingRainflow(idx.size, self._cap)
        other._stack[:] = self._stack[idx]
        other._depth[:] = self._depth[idx]
        other._last = None if self._last is None else self._last[idx].copy()
        return other

    @staticmethod
    def join(parts: list[StreamingRainflow]) -> StreamingRainflow:
        """One counter of the histories of ``parts``, in order (states copied). Every part
        must have been fed as far (all fed, or none): their ``feed`` calls continue alike."""
        fed = {p._last is not None for p in parts if p.n}
        if len(fed) > 1:
            raise ValueError("cannot join a counter that was fed with one that was not")
        cap = max([p._cap for p in parts] + [64])
        out = StreamingRainflow(sum(p.n for p in parts), cap)
        i = 0
        for p in parts:
            out._stack[i:i + p.n, : p._cap] = p._stack
            out._depth[i:i + p.n] = p._depth
            i += p.n
        if fed == {True}:
            out._last = np.concatenate([p._last for p in parts if p._last is not None])
        return out

    def _grow(self) -> None:
        new = np.zeros((self.n, 2 * self._cap))
        new[:, : self._cap] = self._stack
        self._stack, self._cap = new, 2 * self._cap

    # -- counting ------------------------------------------------------------------------
    def feed(self, block: np.ndarray) -> Cycles:
        """Advance every history by a block of samples (n_samples, n_series); return the full
        cycles closed: :meth:`feed_packed` of every sample, :data:`FEED_ROWS` rows at a time
        (each history's cycles in the order they close)."""
        x = np.asarray(block, dtype=float)
        if x.ndim != 2 or x.shape[1] != self.n:
            raise ValueError(f"block must have shape (n_samples, {self.n}), got {x.shape}")
        return Cycles.concat([
            self.feed_packed(x[i:i + FEED_ROWS].T.copy().ravel(),
                             np.full(self.n, min(FEED_ROWS, x.shape[0] - i)),
                             x[min(i + FEED_ROWS, x.shape[0]) - 1])
            for i in range(0, x.shape[0], FEED_ROWS)])

    def feed_packed(self, vals: np.ndarray, counts: np.ndarray, last: np.ndarray,
                    start: int = 0) -> Cycles:
        """Advance histories ``start .. start + len(counts)`` by a block given packed:
        ``vals`` (K,) history by history, the block's samples that may be turning points in
        order (one left out must lie strictly between its neighbours, as
        :func:`.turning_eq.kept_equivalent`'s), ``counts`` (k,) how many each, ``last`` (k,)
        their last samples. The full cycles closed (each history's in the order they close;
        histories in order), as :meth:`feed` of the whole block gives them."""
        vals = np.ascontiguousarray(vals, dtype=float)
        counts = np.ascontiguousarray(counts, dtype=np.int64)
        k = counts.size
        if start < 0 or start + k > self.n or int(counts.sum()) != vals.size \
                or np.shape(last) != (k,):
            raise ValueError(f"feed_packed: {vals.size} values, counts of {k} histories "
                             f"from {start} ({self.n} in the counter), last {np.shape(last)}")
        if self._last is None:
            self._last = np.full(self.n, np.nan)
        self._last[start:start + k] = last
        if k == 0 or vals.size == 0:
            return Cycles.empty()
        depth = self._depth[start:start + k]
        need = int((depth + counts).max()) + 1  # each point pushes at most one
        while need > self._cap:
            self._grow()
        build()
        size = (int(depth.sum()) + vals.size) // 2 + 1
        s, b, c = np.empty(size, dtype=np.int64), np.empty(size), np.empty(size)
        nc = _rainflow_packed(vals, counts, start, self._stack, self._depth, s, b, c)
        return Cycles(s[:nc], b[:nc], c[:nc], np.ones(nc))

    def residue_cycles(self, mode: str = "half_cycles") -> Cycles:
        """Cycles of the residue, without changing this counter.

        ``"half_cycles"``: each range between consecutive residue points counts 0.5 (ASTM).
        ``"repeated"``: the residue is fed again (the next pass of a repeated track) and the
        full cycles that close are returned (:meth:`feed_packed` on a copy, each history's
        cycles in the order they close, histories in order).
        """
        if mode not in RESIDUE_MODES:
            raise ValueError(f"residue mode must be one of {RESIDUE_MODES}, got {mode!r}")
        d = self._depth
        if mode == "half_cycles":
            cols = np.arange(max(int(d.max()) - 1, 0))
            valid = cols[None, :] < (d - 1)[:, None]
            i, j = np.nonzero(valid)
            s1 = self._stack[i, j]
            s2 = self._stack[i, j + 1]
            return Cycles(i.astype(np.int64), s1, s2, np.full(i.size, 0.5))
        if int(d.max()) == 0:
            return Cycles.empty()
        keep = np.arange(self._cap)[None, :] < d[:, None]
        return self.copy().feed_packed(self._stack[keep], d.copy(), np.zeros(self.n))


def _rainflow_packed(vals, counts, start, stack, depth, out_s, out_b, out_c):  # type: ignore[no-untyped-def]  # noqa: E501
    """The four-point rule (module docstring), history by history: histories ``start +
    i`` fed ``counts[i]`` values of ``vals`` in order (the stack has room for them); the
    closed cycles (history, b, c) appended to ``out_*``. Returns their number."""
    pos = 0
    nc = 0
    for i in range(counts.size):
        h = start + i
        d = depth[h]
        for j in range(pos, pos + counts[i]):
            x = vals[j]
            if d == 0:
                stack[h, 0] = x
                d = 1
                continue
            top = stack[h, d - 1]
            dx = x - top
            if d >= 2 and dx * (top - stack[h, d - 2]) > 0.0:  # the same direction: extend
                stack[h, d - 1] = x
            elif dx != 0.0:  # a reversal (or NaN): push
                stack[h, d] = x
                d += 1
            else:
                continue
            while d >= 4:
                a = stack[h, d - 4]
                b = stack[h, d - 3]
                c = stack[h, d - 2]
                e = stack[h, d - 1]
                r = abs(b - c)
                if r <= abs(a - b) and r <= abs(c - e):
                    out_s[nc] = h
                    out_b[nc] = b
                    out_c[nc] = c
                    nc += 1
                    stack[h, d - 3] = e
                    d -= 2
                else:
                    break
        depth[h] = d
        pos += counts[i]
    return nc


KERNELS = (("_rainflow_packed", "i8(f8[::1], i8[::1], i8, f8[:, ::1], i8[::1], i8[::1], "
                                 "f8[::1], f8[::1])"),)


def build() -> None:
    """Compile this module's kernel now (or load it from the cache; once)."""
    compile_kernels(globals(), KERNELS)


def count_series(x: np.ndarray, residue: str = "half_cycles") -> Cycles:
    """Rainflow-count one history (convenience for tests and small jobs)."""
    rf = StreamingRainflow(1)
    arr = np.asarray(x, dtype=float).reshape(-1, 1)
    full = rf.feed(arr)
    return Cycles.concat([full, rf.residue_cycles(residue)])


def histogram(cycles: Cycles) -> dict[float, float]:
    """Cycle counts per range, {range: count} (the form ASTM E1049-85 tabulates)."""
    out: dict[float, float] = {}
    for r, n in zip(cycles.range.tolist(), cycles.count.tolist(), strict=True):
        out[r] = out.get(r, 0.0) + n
    return dict(sorted(out.items()))
