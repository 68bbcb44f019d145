"""tracker.schedule: the frame's time budget for verifying candidate boxes and for working out the costly
1-σ terms (a fake clock; no timing)."""

from __future__ import annotations

import numpy as np

from tracker.schedule import Box, SigmaSchedule, SigmaTerms, VerifySchedule

TRACKED: Box = (100, 100, 140, 180)  # holds the prediction below
BIG: Box = (300, 50, 400, 250)
MID: Box = (10, 10, 60, 60)
SMALL: Box = (500, 400, 520, 420)
HINTS = np.array([[120.0, 150.0, 20.0]])


class Clock:
    """A clock that the fake verification below advances by `cost` seconds per box."""

    def __init__(self, cost: float):
        self.t, self.cost = 0.0, cost

    def __call__(self) -> float:
        return self.t


def run(s: VerifySchedule, clock: Clock, boxes: list[Box]) -> tuple[list[Box], list[Box], int]:
    """(verified boxes in verification order, the results in return order, boxes put off)."""
    order: list[Box] = []

    def verify(b: Box, may_search: object = None) -> list[Box]:
        order.append(b)
        clock.t += clock.cost
        return [b]
    results, put_off = s.run(boxes, HINTS, verify, start=0.0)
    return order, results, put_off


def test_without_a_budget_every_box_is_verified_in_the_candidates_order() -> None:
    clock = Clock(1.0)
    boxes = [SMALL, TRACKED, BIG, MID]
    order, results, put_off = run(VerifySchedule(None, clock), clock, boxes)
    assert order == boxes and results == boxes and put_off == 0


def test_a_spent_budget_puts_off_untracked_boxes_but_never_a_tracked_one_nor_the_first_untracked() -> None:
    clock = Clock(0.003)  # 3 ms per box against a 4 ms budget
    s = VerifySchedule(4.0, clock)
    order, results, put_off = run(s, clock, [SMALL, TRACKED, BIG, MID])
    # the tracked box first, then the largest untracked one (always one), then the budget is spent
    assert order == [TRACKED, BIG]
    assert results == [TRACKED, BIG]  # in the candidates' order
    assert put_off == 2
    # next frame: a box put off comes first among the untracked (the larger of them), before the larger BIG
    clock.t = 0.0
    order, results, put_off = run(s, clock, [BIG, SMALL, MID, TRACKED])
    assert order == [TRACKED, MID]
    assert results == [MID, TRACKED] and put_off == 2


def test_within_the_budget_the_results_are_those_of_no_budget() -> None:
    clock = Clock(0.0001)
    boxes = [SMALL, TRACKED, BIG, MID]
    _, results, put_off = run(VerifySchedule(4.0, clock), clock, boxes)
    assert results == boxes and put_off == 0


TRACKED2: Box = (200, 100, 240, 180)
HINTS2 = np.array([[120.0, 150.0, 20.0], [220.0, 150.0, 20.0]])


def test_a_spent_budget_puts_off_the_new_object_search_beside_a_tracked_object_once_a_frame() -> None:
    clock = Clock(0.003)  # 3 ms per region searched
    s = VerifySchedule(4.0, clock)
    asked: list[tuple[Box, bool]] = []

    def verify(b: Box, may_search: object = None) -> list[Box]:
        clock.t += clock.cost  # the tracked object itself
        assert callable(may_search)  # a tracked box: its other regions go through the budget
        ok = bool(may_search())
        asked.append((b, ok))
        if ok:
            clock.t += clock.cost  # the region beside it, searched over the whole disparity range
            return [b, b]  # and a new object found there
        return [b]
    results, put_off = s.run([TRACKED, TRACKED2], HINTS2, verify, start=0.0)
    # 3 ms: the first box's other region is searched (within 4 ms); at 9 ms the second's is put off
    assert asked == [(TRACKED, True), (TRACKED2, False)] and results == [TRACKED, TRACKED, TRACKED2]
    assert put_off == 1
    clock.t, asked[:] = 0.0, []
    _, put_off = s.run([TRACKED, TRACKED2], HINTS2, verify, start=0.0)
    # next frame: the box put off comes first and is searched within the budget; the other is put off
    assert asked == [(TRACKED2, True), (TRACKED, False)] and put_off == 1
    for late in (TRACKED, TRACKED2, TRACKED):  # each frame starts late: one box put off passes, in turn
        clock.t, asked[:] = 0.01, []
        _, put_off = s.run([TRACKED, TRACKED2], HINTS2, verify, start=0.0)
        assert asked == [(late, True), (TRACKED2 if late == TRACKED else TRACKED, False)] and put_off == 1


def test_searches_past_the_budget_that_find_nothing_back_off() -> None:
    clock = Clock(0.003)
    s = VerifySchedule(1.0, clock)  # every frame is late by its first box
    searched: list[int] = []

    def beside(frame: int) -> object:
        def verify(b: Box, may_search: object = None) -> list[Box]:
            clock.t += clock.cost
            assert callable(may_search)
            if may_search():
                searched.append(frame)  # searched beside the tracked object, in vain
            return [b]
        return verify

    for frame in range(40):
        clock.t = 0.0
        _, put_off = s.run([TRACKED], HINTS, beside(frame), start=0.0)
        assert put_off == (0 if searched and searched[-1] == frame else 1)
    # put off in frame 0, then searched after waiting 0, 1, 2, 4, 8, 8, ... frames
    assert searched == [1, 3, 6, 11, 20, 29, 38]

    searched.clear()
    s = VerifySchedule(1.0, clock)

    def two_regions(frame: int) -> object:  # two fruitless regions beside the tracked object: the same
        def verify(b: Box, may_search: object = None) -> list[Box]:
            clock.t += clock.cost
            assert callable(may_search)
            searched.extend([frame] if may_search() else [])
            searched.extend([frame] if may_search() else [])  # at most one search past the budget a frame
            return [b]
        return verify

    for frame in range(12):
        clock.t = 0.0
        s.run([TRACKED], HINTS, two_regions(frame), start=0.0)
    assert searched == [1, 3, 6, 11]

    untracked: list[int] = []
    now = [0]

    def verify(b: Box, may_search: object = None) -> list[Box]:
        clock.t += clock.cost
        if b == SMALL:
            untracked.append(now[0])
        return [] if b == SMALL else [b]
    for now[0] in range(20):
        clock.t = 0.0
        s.run([TRACKED, SMALL], HINTS, verify, start=0.0)
    assert untracked == [0, 2, 5, 10, 19]  # the first untracked box: at once, then backing off
    clock.t, now[0] = 0.0, 20
    VerifySchedule(1.0, clock).run([TRACKED, SMALL], HINTS, verify, start=0.0)
    assert untracked[-1] == 20  # a new schedule: no back-off


def test_without_a_budget_nothing_asks_before_searching() -> None:
    seen: list[object] = []
    VerifySchedule(None).run([TRACKED, SMALL], HINTS, lambda b, may_search: seen.append(may_search) or [b])
    assert seen == [None, None]


class Terms:
    """A fake SigmaTerms worker that counts its calls and advances the clock by `cost` s."""

    def __init__(self, clock: Clock, cost: float):
        self.clock, self.cost, self.calls = clock, cost, 0

    def __call__(self) -> SigmaTerms:
        self.calls += 1
        self.clock.t += self.cost
        return SigmaTerms(0.01 * self.calls, (0.1 * self.calls, 0.2 * self.calls))


def test_sigma_terms_are_worked_out_every_frame_without_a_budget() -> None:
    clock = Clock(0.0)
    s = SigmaSchedule(None, clock=clock)
    work = Terms(clock, 1.0)
    clock.t = 100.0  # however late the frame
    got = [s.terms(7, i, 0.0, work) for i in range(5)]
    assert work.calls == 5 and got[-1] == SigmaTerms(0.05, (0.5, 1.0)) and s.reused == 0


def test_a_late_frame_keeps_a_tracked_targets_recent_terms_and_works_out_new_or_old_ones() -> None:
    clock = Clock(0.0)
    s = SigmaSchedule(budget_ms=4.0, max_age=3, clock=clock)
    work = Terms(clock, 0.0)
    first = s.terms(1, 10, 0.0, work)  # on time: worked out
    clock.t = 0.005  # 5 ms into the step: late
    assert s.terms(1, 11, 0.0, work) is first and s.terms(1, 13, 0.0, work) is first  # 1 and 3 frames old
    assert work.calls == 1 and s.reused == 2
    clock.t = 0.0055  # 4 frames old: the terms may end by 4 ms · 4/3 = 5.3 ms; 5.5 ms is too late
    assert s.terms(1, 14, 0.0, work) is first and s.reused == 3
    clock.t = 0.005  # 5 ms: in time
    newer = s.terms(1, 14, 0.0, work)
    assert work.calls == 2 and newer != first
    clock.t = 0.007  # 5 frames old: by 6.7 ms, kept; 6 frames old (twice max_age): always worked out
    assert s.terms(1, 19, 0.0, work) is newer and work.calls == 2
    assert s.terms(1, 20, 0.0, work) != newer and work.calls == 3
    s.terms(2, 20, 0.0, work)  # a new track: always worked out
    assert work.calls == 4
    clock.t = 0.001  # on time again: worked out afresh
    s.terms(1, 21, 0.0, work)
    assert work.calls == 5 and s.reused == 4


def test_sigma_terms_of_ended_tracks_are_forgotten() -> None:
    clock = Clock(0.0)
    s = SigmaSchedule(budget_ms=1.0, clock=clock)
    work = Terms(clock, 0.0)
    s.terms(1, 0, 0.0, work)
    s.terms(2, 0, 0.0, work)
    s.keep_only([2])
    clock.t = 1.0  # late
    s.terms(1, 1, 0.0, work)  # forgotten: worked out again
    s.terms(2, 1, 0.0, work)  # kept
    assert work.calls == 3 and s.reused == 1


def test_terms_that_would_end_past_the_budget_by_their_last_cost_are_kept() -> None:
    clock = Clock(0.0)
    s = SigmaSchedule(budget_ms=4.0, clock=clock)
    work = Terms(clock, 0.002)  # 2 ms to work out
    first = s.terms(1, 0, 0.0, work)
    clock.t = 0.0015  # 1.5 ms into the next step: 1.5 + 2 <= 4, worked out
    second = s.terms(1, 1, 0.0, work)
    assert work.calls == 2 and second != first
    clock.t = 0.0025  # 2.5 + 2 > 4 though the budget is not spent yet: kept
    assert s.terms(1, 2, 0.0, work) is second and work.calls == 2 and s.reused == 1
    clock.t = 0.0025
    s.terms(2, 2, 0.0, work)  # a new track: worked out whatever it costs
    assert work.calls == 3


def test_with_later_a_search_past_the_budget_waits_for_between_frames_and_backs_off_there() -> None:
    clock = Clock(0.003)
    s = VerifySchedule(1.0, clock, later=True)  # every frame is late by its first box
    order, results, put_off = run(s, clock, [TRACKED, SMALL])
    assert order == [TRACKED] and results == [TRACKED] and put_off == 1  # SMALL is not searched in the frame
    assert s.take_later() == [SMALL] and s.take_later() == []  # but left for between frames, once

    asked: list[bool] = []

    def beside(b: Box, may_search: object = None) -> list[Box]:
        clock.t += clock.cost
        assert callable(may_search)
        asked.append(bool(may_search()))
        return [b]
    offered: list[int] = []
    for frame in range(1, 20):
        clock.t = 0.0
        s.run([TRACKED], HINTS, beside)
        later = s.take_later()
        if later:
            assert later == [TRACKED]
            offered.append(frame)
            s.searched_later(TRACKED, found=False)  # searched between frames, in vain
    assert not any(asked)  # never searched inside the frame
    assert offered == [2, 4, 7, 12]  # put off in frame 1, then left for between frames after 0, 1, 2, 4 frames
    clock.t = 0.0
    s.run([TRACKED], HINTS, beside)  # frame 20: still waiting
    assert s.take_later() == []
    clock.t = 0.0
    s.run([TRACKED], HINTS, beside)  # frame 21: after 8 frames, the next search
    assert s.take_later() == [TRACKED]
    s.searched_later(TRACKED, found=True)  # it finds something: no back-off, the next frame may leave one
    clock.t = 0.0
    s.run([TRACKED], HINTS, beside)
    assert s.take_later() == [TRACKED] and not any(asked)

    taken = s.take_later()  # nothing left now; a search taken for between frames but not made ...
    clock.t = 0.0
    s.run([TRACKED], HINTS, beside)
    s.not_made(s.take_later())
    clock.t = 0.0
    s.run([TRACKED], HINTS, beside)  # ... is made by the next frame itself
    assert taken == [] and asked[-1] is True and s.take_later() == []


def test_terms_worked_out_between_frames_are_taken_by_the_next_frame_as_they_are() -> None:
    clock = Clock(0.0)
    s = SigmaSchedule(budget_ms=4.0, clock=clock)
    work = Terms(clock, 0.001)
    s.terms(1, 0, 0.0, work)  # a new track: worked out in the frame
    assert not s.refresh(1, 0, 1.0, work)  # already of frame 0
    assert s.refresh(1, 1, 1.0, work) and work.calls == 2  # frame 1's, between frames 1 and 2
    between = s.terms(1, 2, 0.0, work)  # on time, but taken as they are: 1 frame old
    assert work.calls == 2 and s.reused == 1 and s.refreshed == 1
    assert between == SigmaTerms(0.02, (0.2, 0.4))
    clock.t = 0.0
    s.terms(1, 3, 0.0, work)  # 2 frames old and on time: worked out in the frame again
    assert work.calls == 3
    clock.t = 5.0
    assert not s.refresh(1, 3, 5.0005, work)  # by their last cost (1 ms) they would end past the deadline
    assert work.calls == 3
    s2 = SigmaSchedule(None, clock=clock)  # no budget: every frame works them out, none between frames
    s2.terms(1, 0, 0.0, work)
    assert not s2.refresh(1, 1, 100.0, work)
    s2.terms(1, 2, 0.0, work)
    assert work.calls == 5 and s2.refreshed == 0
