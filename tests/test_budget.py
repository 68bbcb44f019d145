"""tracker.budget: a frame's small candidate boxes are verified a few at a time, the longest-waiting
first; large boxes and boxes with a predicted track inside are always verified."""

from __future__ import annotations

import numpy as np
import pytest

from tracker.budget import BudgetConfig, VerifyBudget


def _small_boxes(n: int) -> list[tuple[int, int, int, int]]:
    return [(40 * i, 100, 40 * i + 24, 124) for i in range(n)]


def test_every_small_box_is_verified_within_ceil_n_over_per_frame_frames() -> None:
    budget = VerifyBudget((120, 160), 4, BudgetConfig(small_cells=2, per_frame=4))
    boxes = tuple(_small_boxes(10))
    cells = dict.fromkeys(boxes, 1)
    seen: set[tuple[int, int, int, int]] = set()
    for frame in range(3):
        chosen = budget.select(boxes, cells, None)
        assert len(chosen) == 4 if frame < 2 else len(chosen) in (2, 4)
        assert list(chosen) == [b for b in boxes if b in chosen]  # the candidates' order is kept
        seen |= set(chosen)
    assert seen == set(boxes)
    assert budget.deferred == 6 + 6 + 6


def test_large_and_tracked_boxes_are_always_verified() -> None:
    budget = VerifyBudget((120, 160), 4, BudgetConfig(small_cells=2, per_frame=1))
    small = _small_boxes(5)
    large = (300, 300, 400, 420)
    boxes = (*small, large)
    cells = {**dict.fromkeys(small, 2), large: 40}
    hint = np.array([[small[3][0] + 5.0, small[3][1] + 5.0, 10.0]])  # a track predicted inside box 3
    for _ in range(6):
        chosen = budget.select(boxes, cells, hint)
        assert large in chosen and small[3] in chosen
        assert len(chosen) == 3  # one small box besides the tracked one


def test_a_residual_that_drifts_by_a_cell_keeps_its_turn() -> None:
    budget = VerifyBudget((120, 160), 4, BudgetConfig(small_cells=2, per_frame=1))
    a, b = (0, 0, 24, 24), (200, 200, 224, 224)
    assert budget.select((a, b), {a: 1, b: 1}, None) == (a,)
    a2 = (4, 0, 28, 24)  # a moved by one stride cell: it was just verified, so b goes first
    assert budget.select((a2, b), {a2: 1, b: 1}, None) == (b,)
    assert budget.select((a2, b), {a2: 1, b: 1}, None) == (a2,)


def test_no_bound_and_bad_settings() -> None:
    budget = VerifyBudget((120, 160), 4, BudgetConfig(per_frame=0))
    boxes = tuple(_small_boxes(10))
    assert budget.select(boxes, dict.fromkeys(boxes, 1), None) == boxes
    with pytest.raises(ValueError, match="per_frame"):
        BudgetConfig(per_frame=-1)
