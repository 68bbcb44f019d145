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
spent, one such box put off the frame before is searched a frame, the others put off again. A search
past the budget that finds nothing backs off (1, 2, 4, then MAX_WAIT frames before the next one there).
Without a budget every box is verified, in the candidate stage's order, as before.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TypeVar

import numpy as np
from numpy.typing import NDArray

from tracker.detect import Box, holds_prediction, predictions_in

T = TypeVar("T")


def _overlaps(a: Box, b: Box) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


@dataclass
class _PutOff:
    """A box put off to a later frame. strikes: its searches in a row made past the budget that found
    nothing; wait: frames before the next such search may be made (its back-off)."""

    box: Box
    strikes: int = 0
    wait: int = 0


class _Frame:
    """One frame's bookkeeping: the deadline, the boxes put off the frame before, and what this frame
    puts off or searched past the budget in vain. A search past the budget is made at most once a frame
    for untracked boxes and once for the regions beside tracked objects (`passed`), and only for a box
    whose back-off has run out."""

    def __init__(self, deadline: float, before: list[_PutOff]):
        self.deadline = deadline
        self.before = before
        self.put_off: dict[Box, _PutOff] = {}  # put off, or searched past the budget in vain (that wins)
        self.deferred: set[Box] = set()  # put off
        self.passed = {"untracked": False, "beside": False}

    def prior(self, box: Box) -> _PutOff | None:
        return next((p for p in self.before if _overlaps(box, p.box)), None)

    def may_pass(self, box: Box, kind: str, first_time_ok: bool) -> bool:
        """Whether a box past the deadline is searched now (marking the frame's pass as used)."""
        p = self.prior(box)
        if self.passed[kind] or (p is None and not first_time_ok) or (p is not None and p.wait > 0):
            return False
        self.passed[kind] = True
        return True

    def put(self, box: Box) -> None:
        p = self.prior(box)
        self.put_off.setdefault(box, _PutOff(box, p.strikes if p else 0, max(p.wait - 1, 0) if p else 0))
        self.deferred.add(box)

    def in_vain(self, box: Box) -> None:
        """A search past the budget found nothing: the box waits 1, 2, 4, then MAX_WAIT frames before
        the next one."""
        p = self.prior(box)
        strikes = (p.strikes if p else 0) + 1
        self.put_off[box] = _PutOff(box, strikes, min(2 ** (strikes - 1), VerifySchedule.MAX_WAIT))


class VerifySchedule:
    """Orders and bounds a frame's box verifications. budget_ms None: no bound (evaluations, offline).

    Searches made past the budget (the first untracked box of a frame, or a region beside a tracked
    object put off the frame before) that find nothing back off: the same place is searched past the
    budget again after 1, 2, 4 and then every MAX_WAIT frames (0.27 s at 30 fps) until it finds
    something or is searched within the budget. A lasting fruitless region (leaves, the ragged shadow of
    a tracked object) so costs one search in 8 busy frames instead of one in 2."""

    MAX_WAIT = 8

    def __init__(self, budget_ms: float | None = None, clock: Callable[[], float] = time.perf_counter,
                 later: bool = False):
        """later: a search past the budget is not made in the frame but left for the time between frames
        (`take_later`, `searched_later`): the frame's step then ends within about the budget but for the
        boxes that hold predictions."""
        self.budget_ms = budget_ms
        self.clock = clock
        self.later = later
        self._put_off: list[_PutOff] = []
        self._later: list[Box] = []
        self._missed = False  # the searches left for between frames last time were not all made

    def _order(self, boxes: Sequence[Box], held: list[bool]) -> list[int]:
        """Indices of boxes in the order to verify them: holding a prediction (held), put off last frame,
        then larger first (stable otherwise)."""
        def key(i: int) -> tuple[int, int, int]:
            b = boxes[i]
            put_off = any(_overlaps(b, p.box) for p in self._put_off)
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
        fr = _Frame(t0 + self.budget_ms * 1e-3, self._put_off)
        self._missed, self._later = bool(self._later), []
        done: dict[int, list[T]] = {}
        held = [holds_prediction(b, hints) for b in boxes]
        for i in self._order(boxes, held):
            b = boxes[i]
            if held[i]:
                forced = [False]
                done[i] = verify(b, self._may_search(b, fr, forced))
                if forced[0] and len(done[i]) <= predictions_in(b, hints):
                    fr.in_vain(b)
            elif self.clock() <= fr.deadline:
                fr.passed["untracked"] = True  # the first untracked box, at least, is verified every frame
                done[i] = verify(b, None)
            elif fr.may_pass(b, "untracked", True) and not self._leave(b, fr):
                done[i] = verify(b, None)
                if not done[i]:
                    fr.in_vain(b)
            else:
                fr.put(b)
        self._put_off = list(fr.put_off.values())
        return [r for i in range(len(boxes)) for r in done.get(i, [])], len(fr.deferred)

    def _may_search(self, box: Box, fr: _Frame, forced: list[bool]) -> Callable[[], bool]:
        """Whether a region of a tracked box that holds no prediction (something beside the tracked
        object: a new object, or leaves) is searched now: while the budget lasts; once it is spent, only
        where the box overlaps one put off the frame before whose back-off has run out, once a frame, so
        that what is put off is searched within a frame or two even while tracked objects use up the
        budget (forced[0] set: the caller judges whether it found anything). Else the box is put off."""
        def ask() -> bool:
            if self.clock() <= fr.deadline:
                return True
            if fr.may_pass(box, "beside", False) and not self._leave(box, fr):
                forced[0] = True
                return True
            fr.put(box)
            return False
        return ask

    def _leave(self, box: Box, fr: _Frame) -> bool:
        """With `later`, a search past the budget is left for between frames (the box is put off), unless
        those left the frame before were not all made (no time between frames): then it is made now."""
        leave = self.later and not self._missed
        if leave:
            self._later.append(box)
            fr.put(box)
        return leave

    def take_later(self) -> list[Box]:
        """The searches the last frame left for between frames (at most one untracked box and one box
        beside tracked objects), once. Those not made must be handed back (`not_made`)."""
        later, self._later = self._later, []
        return later

    def not_made(self, boxes: Sequence[Box]) -> None:
        """Searches taken for between frames but not made: the next frame makes its searches itself."""
        self._later.extend(boxes)

    def searched_later(self, box: Box, found: bool) -> None:
        """A search left for between frames was made: one that found nothing backs the box off as a
        search past the budget in vain does; one that found something ends its back-off."""
        p = next((p for p in self._put_off if p.box == box), None)
        if p is not None:
            p.strikes = 0 if found else p.strikes + 1
            p.wait = 0 if found else min(2 ** (p.strikes - 1), self.MAX_WAIT)


@dataclass(frozen=True)
class SigmaTerms:
    """The costly terms of a target's 1-σ (tracker.pipeline): disparity_px, the scatter of its parts'
    disparities (px, tracker.disparity_sigma); centroid_px, the centroid's further 1-σ (px, x and y) where
    it is seen in part or its outline is drawn by warping (tracker.visibility, tracker.outline), and from
    the outline's whole pixels and a body's hull gap (tracker.segmentation), but for the hull gap's x term:
    gap_x_px, apart, for it counts only where the target is not an upright body at the frame the terms are
    used for (tracker.solid_prior.SolidPrior.upright; the terms may be a few frames old); rim_px, a solid
    body's outline's 1-σ (px, x and y) from its rim's contrast (tracker.rim_contrast; None: not known, the
    cameras moving, or no SolidPrior); hidden_below, a nearer background hides the target's bottom (or it lies past the
    image's bottom edge) while its top is seen (tracker.visibility.Cuts; an upright body's centre is then found from its
    top, tracker.localize.Localizer.locate); cut_px, what may be hidden where the target is seen in part (px, x and y:
    the cut sides' kappa term, tracker.visibility.cut_sigma_px, the centroid's move across them and the rows lost
    against the ground, in quadrature), apart from centroid_px: the track's extents seen whole bound it at the frame the
    terms are used for (tracker.extent_history.ExtentHistory); seen_whole, whether its width and its height were seen
    whole (no side along that axis cut, nothing lost against the ground along y); known_person, a track seen whole as an
    upright body whose lower part a nearer background hides now (tracker.extent_history.ExtentHistory.seen_upright): a
    person whatever its top's outline says (tracker.localize.Localizer.locate's upright); rim_shift_px, how far (px, x
    and y) the true silhouette's centroid lies from the outline's where a curved rim's faint sides lost a band
    (tracker.rim_contrast.rim_shift_px), added to the centroid that is located."""

    disparity_px: float
    centroid_px: tuple[float, float]
    gap_x_px: float = 0.0
    rim_px: tuple[float, float] | None = None
    hidden_below: bool = False
    cut_px: tuple[float, float] = (0.0, 0.0)
    seen_whole: tuple[bool, bool] = (True, True)
    known_person: bool = False
    rim_shift_px: tuple[float, float] = (0.0, 0.0)


class SigmaSchedule:
    """Which targets have their SigmaTerms worked out afresh in a frame with a time budget.

    The terms cost 0.3 to 2.5 ms a target; they change slowly (the target's size, texture, what hides
    it). With a budget, a tracked target keeps its terms when working them out again would end after
    budget_ms of the frame's step (by what they cost the last time). Terms older than `max_age` frames
    may end later, the more so the older they are: up to budget_ms · age / max_age; at twice max_age,
    or for a new track, they are always worked out. So a target whose own verification takes the whole
    budget every frame (a near person, while the mount turns) has its terms worked out once in 15 to 30
    frames, in the least busy of those frames rather than in whichever comes 16th. budget_ms None: always
    worked out (evaluations, offline).

    Between frames (`refresh`, in the time left before the next frame is due) the terms of the frame just
    done are worked out for each tracked target; a frame takes those of the frame before as they are, so
    that their cost leaves the step altogether while they stay one frame old."""

    def __init__(self, budget_ms: float | None = None, max_age: int = 15,
                 clock: Callable[[], float] = time.perf_counter):
        self.budget_ms = budget_ms
        self.max_age = max_age
        self.clock = clock
        # track id -> (frame index, terms, cost ms, worked out between frames)
        self._kept: dict[int, tuple[int, SigmaTerms, float, bool]] = {}
        self.reused = 0  # terms taken from an earlier frame (counted for the status)
        self.refreshed = 0  # terms worked out between frames (`refresh`)

    def terms(self, track_id: int, index: int, start: float, work: Callable[[], SigmaTerms]) -> SigmaTerms:
        """The track's terms at frame `index`: work() when due, else those kept. start: the step's start
        (clock seconds)."""
        kept = self._kept.get(track_id)
        now = self.clock()
        age = index - kept[0] if kept is not None else -1
        if self.budget_ms is not None and kept is not None and (
                (age == 1 and kept[3]) or (0 <= age < 2 * self.max_age and (now - start) * 1e3 + kept[2]
                                           > self.budget_ms * max(1.0, age / self.max_age))):
            self.reused += 1
            return kept[1]
        got = work()
        self._kept[track_id] = (index, got, (self.clock() - now) * 1e3, False)
        return got

    def refresh(self, track_id: int, index: int, deadline: float, work: Callable[[], SigmaTerms]) -> bool:
        """Between frames: work out the track's terms of frame `index` (just done) if they are older and,
        by what they cost the last time, would end by `deadline` (clock seconds). Returns whether it did."""
        kept = self._kept.get(track_id)
        now = self.clock()
        if self.budget_ms is None or (kept is not None and (kept[0] >= index or now + kept[2] * 1e-3 > deadline)):
            return False  # without a budget every frame works them out itself
        got = work()
        self._kept[track_id] = (index, got, (self.clock() - now) * 1e3, True)
        self.refreshed += 1
        return True

    def keep_only(self, track_ids: Sequence[int]) -> None:
        """Forget the terms of tracks not in track_ids (ended)."""
        live = set(track_ids)
        self._kept = {i: v for i, v in self._kept.items() if i in live}
