"""Candidate boxes of eq. (9)'s cells joined where they hold one object's parts (tracker.detect)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Box = tuple[int, int, int, int]  # raw left pixels: x0, y0, x1, y1


def _stacked(a: Box, b: Box, gap_px: int = 8) -> bool:
    """Whether two boxes lie one above the other, overlapping or at most gap_px apart: across most of the
    narrower one's width, along at most half the shorter one's height."""
    ox = min(a[2], b[2]) - max(a[0], b[0])
    oy = min(a[3], b[3]) - max(a[1], b[1])
    return (ox >= 0.5 * min(a[2] - a[0], b[2] - b[0]) and -gap_px <= oy <= 0.5 * min(a[3] - a[1], b[3] - b[1]))


def stacked_joined(boxes: list[Box], cells: list[int]) -> tuple[tuple[Box, ...], tuple[int, ...]]:
    """Boxes one above the other, overlapping or a few pixels apart (_stacked), joined into their bounding
    box, their cells added: eq. (9) fires on a standing walker's torso against a hedge and on its feet, but
    not on the knees between, over ground at nearly their depth (endless:body, 69 frames of a walker's legs
    left out); its parts are verified together (tracker.verify takes several objects from one box). Boxes
    side by side (a car split by a post) stay apart: joined so, occlusion:plate had 3 false-target frames
    and a range NEES of 24."""
    out, n = list(boxes), list(cells)
    joined = True
    while joined:
        joined = False
        pairs = ((i, j) for i in range(len(out)) for j in range(i + 1, len(out)))
        hit = next(((i, j) for i, j in pairs if _stacked(out[i], out[j])), None)
        if hit is not None:
            i, j = hit
            a, b = out[i], out.pop(j)
            out[i] = (min(a[0], b[0]), min(a[1], b[1]), max(a[2], b[2]), max(a[3], b[3]))
            n[i] += n.pop(j)
            joined = True
    return tuple(out), tuple(n)


class TrackSpans:
    """How far each track's outline reached above and below its centroid over its last `frames` frames, per
    unit disparity (a body's height in the image scales with d), to widen the candidate box its predicted
    centroid lies in along y (`widened`): eq. (9) may fire on a standing walker's torso only, its legs over
    ground at nearly their depth, and the temporal model and the outline's growth (tracker.growth) see no
    further than the box."""

    def __init__(self, frames: int = 15):
        self.frames = frames
        self._kept: dict[int, list[tuple[float, float]]] = {}

    def keep(self, track_id: int, box: Box, mask: NDArray[np.bool_], cy: float, d: float) -> None:
        """Add a track's outline this frame: its mask over box (raw left px), its centroid's row cy, its d."""
        rows = np.flatnonzero(mask.any(axis=1))
        if d <= 0 or rows.size == 0:
            return
        seen = self._kept.setdefault(track_id, [])
        seen.append(((cy - box[1] - int(rows[0])) / d, (box[1] + int(rows[-1]) + 1 - cy) / d))
        del seen[:-self.frames]

    def keep_only(self, track_ids: list[int]) -> None:
        self._kept = {k: v for k, v in self._kept.items() if k in track_ids}

    def widened(self, boxes: tuple[Box, ...], hints: NDArray[np.float64], ids: list[int], height: int,
                margin_px: int) -> tuple[Box, ...]:
        """Each box that holds a track's predicted centroid (hints: (N, 3) x, y, d, raw left px; ids: their
        tracks) reaching over the rows that track's outline reached lately (the most above and below its
        centroid, times the predicted d), plus margin_px, within the image's `height`."""
        out = []
        for x0, y0, x1, y1 in boxes:
            for (x, y, d), k in zip(hints, ids, strict=True):
                seen = self._kept.get(k)
                if not seen or not (x0 <= x < x1 and y0 <= y < y1):
                    continue
                up, down = max(s[0] for s in seen), max(s[1] for s in seen)
                y0 = max(min(y0, int(np.floor(y - up * d)) - margin_px), 0)
                y1 = min(max(y1, int(np.ceil(y + down * d)) + margin_px + 1), height)
            out.append((x0, y0, x1, y1))
        return tuple(out)
