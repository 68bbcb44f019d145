"""How far off the centroid of eq. (10) may lie because the outline itself is imperfect (issue 12 item 1).

Three terms, from the mask and the track's recent masks alone (no truth), each a 1-σ in px along x and y
(y only for the last), added in quadrature to the centroid's other terms (tracker.pipeline):

`edge_quantisation_px`: an outline is a set of whole pixels. Each edge pixel stands for a piece of the true
outline that covers some fraction of it, unknown and evenly spread over [0, 1] as the target moves by
fractions of a pixel: a pixel's worth of area off by 1/√12 px² rms, edge pixel by edge pixel, and
independent along the edge, since whether a partly covered pixel passes the threshold depends on the
target's texture and the background behind it there. An edge pixel put in or left out moves the
centroid by (its position - the centroid) / the area (as in tracker.outline, whose warped edges are off by
more), so

    σ_cx² = Σ_edge (x_i - c_x)² / (12 A²),   σ_cy² = Σ_edge (y_i - c_y)² / (12 A²)   (px², A in px).

For a W x H px plate that is about 1 / (24 H) + W / (72 H²): 0.037 px for 40 x 40 px, in place of the
fixed 0.05 px floor that made the angles' 1-σ of clean, fully seen plates too large (walk: azimuth NEES
0.57, elevation 0.45).

`hull_gap_px`: a solid, textured, shaded body (a person, a vehicle) is not segmented whole: faces turned
from the light, a texture like the background, the gap at the neck leave parts of it out (about 17 % of a
person's silhouette in the simulated scenes), and what is left out lies in notches of the outline. The
pixels inside the mask's convex hull but not in the mask (the hull gap, n_g px) are each either background
seen through a concave outline (between the legs) or the target missed; which, one frame cannot tell. If a
share u of them is the target, the centroid moves by u n_g / (A + u n_g) times their offset from it; with u
unknown and evenly spread over [0, 1] (rms 1/√3), and the gap's pixels at their rms distance from the
centroid along each axis,

    σ_gx = κ s √(mean_gap (x - c_x)²),   s = n_g / (A + n_g),   κ = 1/√3.

A convex outline (a plate, a sphere seen whole) has no gap and no such term; a merged or badly cut mask, a
large one. The pixels a body loses beyond the hull (a head past the neck's gap) are not in it.

`HeightHistory`: a piece lost or gained at the top or bottom shows as a change of the outline's height that
the target's change of range does not explain (see the class). The first two cost about 0.15 ms a target
together and go through tracker.schedule.SigmaSchedule; the third, a few µs, is worked out every frame.
"""

from __future__ import annotations

import statistics

import cv2
import numpy as np
from numpy.typing import NDArray

BoolA = NDArray[np.bool_]
_CROSS = cv2.getStructuringElement(cv2.MORPH_CROSS, (3, 3))
EDGE_PX = 1.0 / np.sqrt(12.0)  # rms error of one edge pixel's coverage (px²: one pixel's area)
KAPPA = 1.0 / np.sqrt(3.0)  # rms of the unknown share of the hull gap that is the target


def edge_quantisation_px(mask: BoolA) -> tuple[float, float]:
    """The centroid's 1-σ (px, x and y) from the whole-pixel outline: EDGE_PX times the root sum of the
    squared distances of the mask's edge pixels (a 4-neighbour outside it) from its centroid, over its
    area. mask: (h, w) bool, any origin. (0, 0) for an empty mask."""
    return outline_sigma_px(mask)[0]


def hull_gap_px(mask: BoolA, kappa: float = KAPPA) -> tuple[float, float]:
    """The centroid's 1-σ (px, x and y) from the mask's hull gap (the pixels of its convex hull, drawn
    through its outline's pixel centres, that are not in it, the hull's own 1-px rim left out): kappa x
    the gap's share of mask and gap x the gap pixels' rms distance from the mask's centroid along each
    axis. mask: (h, w) bool, any origin. (0, 0) for an empty or convex mask."""
    return outline_sigma_px(mask, kappa)[1]


def outline_sigma_px(mask: BoolA, kappa: float = KAPPA) -> tuple[tuple[float, float], tuple[float, float]]:
    """`edge_quantisation_px` and `hull_gap_px` of a mask at once: ((x, y), (x, y)) in px. The mask, its
    edge and its hull gap are summed along the columns and rows in one pass (cv2.reduce over the three as
    channels), their centroids and spreads taken from those sums. About 0.15 ms for a walker's 100 x 45 px
    mask in the pipeline."""
    bx, by, bw, bh = cv2.boundingRect(mask.view(np.uint8))
    if bw == 0:
        return (0.0, 0.0), (0.0, 0.0)
    m8 = np.ascontiguousarray(mask.view(np.uint8)[by:by + bh, bx:bx + bw])  # the work scales with the box
    edge = cv2.subtract(m8, cv2.erode(m8, _CROSS, borderType=cv2.BORDER_CONSTANT, borderValue=0))
    contours, _ = cv2.findContours(m8, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    filled = np.zeros_like(m8)
    cv2.fillConvexPoly(filled, cv2.convexHull(np.concatenate(contours)), 1)
    # the hull's own rim left out: a digitised convex outline (a disc) differs from its hull's there
    gap = cv2.subtract(cv2.erode(filled, _CROSS, borderType=cv2.BORDER_CONSTANT, borderValue=0), m8)
    three = cv2.merge([m8, edge, gap])
    cols = cv2.reduce(three, 0, cv2.REDUCE_SUM, dtype=cv2.CV_64F).reshape(-1, 3)  # (w, 3): Σ per column
    rows = cv2.reduce(three, 1, cv2.REDUCE_SUM, dtype=cv2.CV_64F).reshape(-1, 3)  # (h, 3)
    x, y = np.arange(bw, dtype=np.float64), np.arange(bh, dtype=np.float64)
    n, sx, sy, sxx, syy = cols.sum(axis=0), x @ cols, y @ rows, (x * x) @ cols, (y * y) @ rows
    cx, cy = sx[0] / n[0], sy[0] / n[0]
    # Σ (x - cx)², Σ (y - cy)² of the edge's (1) and the gap's (2) pixels about the mask's centroid
    vx = np.maximum(sxx - 2.0 * cx * sx + cx * cx * n, 0.0)
    vy = np.maximum(syy - 2.0 * cy * sy + cy * cy * n, 0.0)
    edge_px = (float(EDGE_PX * np.sqrt(vx[1]) / n[0]), float(EDGE_PX * np.sqrt(vy[1]) / n[0]))
    if n[2] == 0:
        return edge_px, (0.0, 0.0)
    share = kappa * n[2] / (n[0] + n[2])
    return edge_px, (float(share * np.sqrt(vx[2] / n[2])), float(share * np.sqrt(vy[2] / n[2])))


class HeightHistory:
    """The outline's height per track over its last `frames` frames, to tell a piece of the target lost or
    gained at its top or bottom (a head past the neck's gap, feet against the ground, another object
    merged) from the target's own change of size.

    A target's image height scales with its disparity (h / d is its height in metres over f b) and, for a
    walker, hardly changes with its gait (its legs and arms swing across the line of sight: they change
    the outline's width by a fifth within a stride, symmetrically about its centre, but not its height).
    So where the height differs from the median of the last frames' h / d times this frame's d by more
    than the pixel the outline's ends may round to, the difference is a piece lost or gained at one end:
    it moves the centroid by about half of it, the 1-σ added along y. Cheap (a median of at most
    `frames` numbers): worked out every frame, not through the SigmaSchedule."""

    def __init__(self, frames: int = 15, min_frames: int = 3, max_gap: int = 3, round_px: float = 1.0):
        self.frames = frames
        self.min_frames = min_frames
        self.max_gap = max_gap
        self.round_px = round_px
        self._kept: dict[int, tuple[int, list[float]]] = {}  # track id -> (last frame index, h / d values)

    def sigma_px(self, track_id: int, index: int, height_px: float, disparity: float) -> float:
        """The centroid's further 1-σ along y (px) for the track's outline of height_px at frame `index`
        with disparity `disparity` (px), and the height kept for the next frames. 0 until the track has
        min_frames heights from frames at most max_gap apart."""
        if disparity <= 0:
            return 0.0
        last, seen = self._kept.get(track_id, (index, []))
        if index - last > self.max_gap or index < last:
            seen = []
        out = 0.0
        if len(seen) >= self.min_frames:
            expected = statistics.median(seen) * disparity  # a few µs on 15 floats, unlike np.median
            out = 0.5 * max(abs(height_px - expected) - self.round_px, 0.0)
        seen = (seen + [height_px / disparity])[-self.frames:]
        self._kept[track_id] = (index, seen)
        return out

    def keep_only(self, track_ids: list[int]) -> None:
        """Forget the heights of tracks not in track_ids (ended)."""
        live = set(track_ids)
        self._kept = {i: v for i, v in self._kept.items() if i in live}
