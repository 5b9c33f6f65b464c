"""The steps a channel has delivered, as sorted disjoint ranges: memory by the number of
holes, not the number of steps."""

from __future__ import annotations

from bisect import bisect_right


class StepSet:
    """Steps ``k`` >= 0 received, as half-open ranges ``[lo, hi)``; ``count`` of them."""

    __slots__ = ("lo", "hi", "count")

    def __init__(self) -> None:
        self.lo: list[int] = []
        self.hi: list[int] = []
        self.count = 0

    def add(self, k: int) -> bool:
        """Add step ``k``; False when it was already there (a duplicate)."""
        lo, hi = self.lo, self.hi
        if hi and k == hi[-1]:  # the usual case: the next step in order
            hi[-1] += 1
            self.count += 1
            return True
        i = bisect_right(lo, k) - 1  # the range starting at or before k
        if i >= 0 and k < hi[i]:
            return False
        joins_left = i >= 0 and hi[i] == k
        joins_right = i + 1 < len(lo) and lo[i + 1] == k + 1
        if joins_left and joins_right:
            hi[i] = hi[i + 1]
            del lo[i + 1], hi[i + 1]
        elif joins_left:
            hi[i] = k + 1
        elif joins_right:
            lo[i + 1] = k
        else:
            lo.insert(i + 1, k)
            hi.insert(i + 1, k + 1)
        self.count += 1
        return True

    def __contains__(self, k: int) -> bool:
        i = bisect_right(self.lo, k) - 1
        return i >= 0 and k < self.hi[i]
