"""tracker.schedule: the frame's time budget for verifying candidate boxes (a fake clock; no timing)."""

from __future__ import annotations

import numpy as np

from tracker.schedule import Box, VerifySchedule

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

    def verify(b: Box) -> list[Box]:
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
