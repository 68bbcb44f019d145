"""A bound on one frame's verification work (tracker.verify), so that a frame full of stray residuals
does not cost several times an ordinary one.

Candidate boxes of at most `small_cells` stride cells are nearly always stray residuals: over 900
frames of the endless closed loop, 12 of about 2,000 such boxes held an object (0.6 %), while each costs
0.2 to 0.6 ms to verify and a frame may have 20 of them. At most `per_frame` of them are verified per frame,
the ones that have waited longest first; a small object that persists is therefore verified within ⌈n /
per_frame⌉ frames of appearing among n small boxes, and from its first detection on its track's prediction
falls inside its box, which is then always verified. Larger boxes, and boxes with a predicted track position
inside, are always verified.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Box = tuple[int, int, int, int]


@dataclass(frozen=True)
class BudgetConfig:
    """small_cells: a box with at most this many candidate cells is small; per_frame: the small boxes
    verified per frame (0: no bound)."""

    small_cells: int = 5
    per_frame: int = 3

    def __post_init__(self) -> None:
        if self.small_cells < 0 or self.per_frame < 0:
            raise ValueError("small_cells and per_frame must be 0 or more")


class VerifyBudget:
    """`select(boxes, cells, hints)` -> the boxes to verify this frame, in their given order.

    The wait of a small box is counted on the candidate grid (low_shape = (rows, cols) of stride cells):
    each cell keeps the frame it was last verified in, and a box's wait is the frames since the most
    recent of its cells, so a residual that drifts by a cell does not count as new."""

    def __init__(self, low_shape: tuple[int, int], stride: int, config: BudgetConfig | None = None):
        self.cfg = config or BudgetConfig()
        self.stride = stride
        self.verified_at = np.full(low_shape, -1, np.int64)  # frame number, -1: never
        self.frame = 0
        self.deferred = 0  # small boxes left for later frames, since the start

    def _cells(self, b: Box) -> tuple[slice, slice]:
        s = self.stride
        return slice(b[1] // s, (b[3] + s - 1) // s), slice(b[0] // s, (b[2] + s - 1) // s)

    def select(self, boxes: tuple[Box, ...], cells: dict[Box, int],
               hints: NDArray[np.float64] | None) -> tuple[Box, ...]:
        """boxes: the candidates worth verifying; cells: candidate cells per box; hints: predicted track
        positions (n, 2+) in raw left pixels (x, y), or None."""
        self.frame += 1
        cfg = self.cfg

        def tracked(b: Box) -> bool:
            return hints is not None and any(b[0] <= h[0] < b[2] and b[1] <= h[1] < b[3] for h in hints)

        small = [b for b in boxes if cells.get(b, cfg.small_cells + 1) <= cfg.small_cells and not tracked(b)]
        if cfg.per_frame and len(small) > cfg.per_frame:
            wait = {b: self.frame - int(self.verified_at[self._cells(b)].max()) for b in small}
            order = sorted(small, key=lambda b: -wait[b])  # stable: ties keep the candidates' order
            skipped = set(order[cfg.per_frame:])
            self.deferred += len(skipped)
            boxes = tuple(b for b in boxes if b not in skipped)
        for b in boxes:
            self.verified_at[self._cells(b)] = self.frame
        return boxes
