"""Which candidate boxes a frame verifies, and in what order, when the frame has a time budget.

Verification (tracker.verify) costs 0.3 to 1.5 ms per box, so a frame with many candidate boxes (foliage,
a light change, the residuals of a moving view) can take several times the usual time. In real time the
frame is late then, and so is everything that waits for it (the servo command, the telemetry). With a
budget, the boxes that hold a track's predicted position are verified first and always; the others follow,
those put off the frame before first, then the largest. Any but the first of them that would start once
the budget is spent is put off to the next frame, where it comes first: one box that holds no prediction
is verified every frame, so a queue of put-off boxes drains even while tracked ones use up the budget.
Without a budget every box is verified, in the candidate stage's order, as before.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import TypeVar

import numpy as np
from numpy.typing import NDArray

from tracker.detect import Box, holds_prediction

T = TypeVar("T")


def _overlaps(a: Box, b: Box) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


class VerifySchedule:
    """Orders and bounds a frame's box verifications. budget_ms None: no bound (evaluations, offline)."""

    def __init__(self, budget_ms: float | None = None, clock: Callable[[], float] = time.perf_counter):
        self.budget_ms = budget_ms
        self.clock = clock
        self._put_off: tuple[Box, ...] = ()

    def _order(self, boxes: Sequence[Box], held: list[bool]) -> list[int]:
        """Indices of boxes in the order to verify them: holding a prediction (held), put off last frame,
        then larger first (stable otherwise)."""
        def key(i: int) -> tuple[int, int, int]:
            b = boxes[i]
            put_off = any(_overlaps(b, p) for p in self._put_off)
            return (0 if held[i] else 1, 0 if put_off else 1, -(b[2] - b[0]) * (b[3] - b[1]))
        return sorted(range(len(boxes)), key=key)

    def run(self, boxes: Sequence[Box], hints: NDArray[np.float64] | None, verify: Callable[[Box], list[T]],
            start: float | None = None) -> tuple[list[T], int]:
        """verify(box) for the boxes within the budget, counted from `start` (clock seconds; default now).
        Returns the results concatenated in the boxes' own order, and how many boxes were put off."""
        if self.budget_ms is None:
            return [r for b in boxes for r in verify(b)], 0
        t0 = self.clock() if start is None else start
        deadline = t0 + self.budget_ms * 1e-3
        done: dict[int, list[T]] = {}
        put_off: list[Box] = []
        untracked = 0
        held = [holds_prediction(b, hints) for b in boxes]
        for i in self._order(boxes, held):
            b = boxes[i]
            if not held[i]:
                if untracked and self.clock() > deadline:
                    put_off.append(b)
                    continue
                untracked += 1
            done[i] = verify(b)
        self._put_off = tuple(put_off)
        return [r for i in range(len(boxes)) for r in done.get(i, [])], len(put_off)
