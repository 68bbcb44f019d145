"""Which candidate boxes a frame verifies, and in what order, when the frame has a time budget
(`VerifySchedule`); and whose costly 1-σ terms are worked out afresh (`SigmaSchedule`).

Verification (tracker.verify) costs 0.3 to 1.5 ms per box, so a frame with many candidate boxes (foliage,
a light change, the residuals of a moving view) can take several times the usual time. In real time the
frame is late then, and so is everything that waits for it (the servo command, the telemetry). With a
budget, the boxes that hold a track's predicted position are verified first and always; the others follow,
those put off the frame before first, then the largest. Any but the first of them that would start once
the budget is spent is put off to the next frame, where it comes first: one box that holds no prediction
is verified every frame, so a queue of put-off boxes drains even while tracked ones use up the budget.
Inside a tracked box, the regions beside the tracked objects that hold no prediction are searched as new
objects (the costliest verification: over the whole disparity range) under the same budget; once it is
spent, one such box put off the frame before is searched a frame, the others put off again.
Without a budget every box is verified, in the candidate stage's order, as before.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
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

    def run(self, boxes: Sequence[Box], hints: NDArray[np.float64] | None,
            verify: Callable[[Box, Callable[[], bool] | None], list[T]], start: float | None = None
            ) -> tuple[list[T], int]:
        """verify(box, may_search) for the boxes within the budget, counted from `start` (clock seconds;
        default now). may_search: for a box that holds a prediction, asked before each of its regions
        that holds none is searched as a new object (None: always search; see `_may_search`). Returns
        the results concatenated in the boxes' own order, and how many boxes were put off (whole, or
        their regions that hold no prediction)."""
        if self.budget_ms is None:
            return [r for b in boxes for r in verify(b, None)], 0
        t0 = self.clock() if start is None else start
        deadline = t0 + self.budget_ms * 1e-3
        done: dict[int, list[T]] = {}
        put_off: list[Box] = []
        untracked, passed = 0, [False]
        held = [holds_prediction(b, hints) for b in boxes]
        for i in self._order(boxes, held):
            b = boxes[i]
            if not held[i]:
                if untracked and self.clock() > deadline:
                    put_off.append(b)
                    continue
                untracked += 1
                done[i] = verify(b, None)
            else:
                done[i] = verify(b, self._may_search(b, deadline, put_off, passed))
        self._put_off = tuple(dict.fromkeys(put_off))
        return [r for i in range(len(boxes)) for r in done.get(i, [])], len(self._put_off)

    def _may_search(self, box: Box, deadline: float, put_off: list[Box], passed: list[bool]
                    ) -> Callable[[], bool]:
        """Whether a region of a tracked box that holds no prediction (something beside the tracked
        object: a new object, or leaves) is searched now: while the budget lasts; once it is spent, only
        where the box overlaps one put off the frame before, once a frame (passed[0]), so that what is
        put off is searched within a frame or two even while tracked objects use up the budget. Else
        the box is put off."""
        def ask() -> bool:
            if self.clock() <= deadline:
                return True
            if not passed[0] and any(_overlaps(box, p) for p in self._put_off):
                passed[0] = True
                return True
            put_off.append(box)
            return False
        return ask


@dataclass(frozen=True)
class SigmaTerms:
    """The costly terms of a target's 1-σ (tracker.pipeline): disparity_px, the scatter of its parts'
    disparities (px, tracker.disparity_sigma); centroid_px, the centroid's further 1-σ (px, x and y) where
    it is seen in part or its outline is drawn by warping (tracker.visibility, tracker.outline), and from
    the outline's whole pixels and a body's hull gap (tracker.segmentation)."""

    disparity_px: float
    centroid_px: tuple[float, float]


class SigmaSchedule:
    """Which targets have their SigmaTerms worked out afresh in a frame with a time budget.

    The terms cost 0.3 to 2.5 ms a target; they change slowly (the target's size, texture, what hides
    it). With a budget, a tracked target whose terms were worked out within the last `max_age` frames
    keeps them when working them out again would end after budget_ms of the frame's step (by what they
    cost the last time); a new track, or terms older than that, are always worked out. budget_ms None:
    always worked out (evaluations, offline)."""

    def __init__(self, budget_ms: float | None = None, max_age: int = 15,
                 clock: Callable[[], float] = time.perf_counter):
        self.budget_ms = budget_ms
        self.max_age = max_age
        self.clock = clock
        self._kept: dict[int, tuple[int, SigmaTerms, float]] = {}  # track id -> (frame index, terms, cost ms)
        self.reused = 0  # terms taken from an earlier frame (counted for the status)

    def terms(self, track_id: int, index: int, start: float, work: Callable[[], SigmaTerms]) -> SigmaTerms:
        """The track's terms at frame `index`: work() when due, else those kept. start: the step's start
        (clock seconds)."""
        kept = self._kept.get(track_id)
        now = self.clock()
        if (self.budget_ms is not None and kept is not None and 0 <= index - kept[0] <= self.max_age
                and (now - start) * 1e3 + kept[2] > self.budget_ms):
            self.reused += 1
            return kept[1]
        got = work()
        self._kept[track_id] = (index, got, (self.clock() - now) * 1e3)
        return got

    def keep_only(self, track_ids: Sequence[int]) -> None:
        """Forget the terms of tracks not in track_ids (ended)."""
        live = set(track_ids)
        self._kept = {i: v for i, v in self._kept.items() if i in live}
