"""How far off the centroid of eq. (10) may lie because the outline itself is imperfect (issue 12 item 1).

Three terms, from the mask and the track's recent masks alone (no truth), each a 1-σ in px along x and y
(y only for the last), added in quadrature to the centroid's other terms (tracker.pipeline):

`edge_quantisation_px`: an outline is a set of whole pixels. Each row's run of mask pixels ends at a whole
pixel where the true outline crosses the row somewhere within it, unknown and evenly spread over it as the
target moves by fractions of a pixel: that end is off by 1/√12 px rms, and it moves the centroid along x
by (its offset) x (its position - the centroid) / the area; likewise each column's run ends for y. Where
the outline is slanted or curved, it crosses each column of pixels within a few rows (the staircase of
its image) and the ends' errors change from row to row: they are independent. Where it runs straight along
a column (a board's upright side, seen square on), the ends of all its rows there lie at one unknown
offset: they move together, and the centroid with them, by n times as much for a run of n rows. A run
counts as straight when it is longer than a curved outline's can be: the outline of a disc of radius R
(px) stays within one column for about 2√R rows where it turns, a straight side for its whole length, so
runs of at least 2√(2 E) rows (E: the outline's extent along them) are taken as straight, unless they are
steps of a slanted side's staircase (the next steps carry on one column over, to either side). So, over the
runs k of row ends in one column (n_k rows, at x_k) and of column ends in one row (at y_k),

    σ_cx² = Σ_k w_k (x_k - c_x)² / (12 A²),   w_k = n_k² for a straight run, n_k otherwise   (px², A in px)

and σ_cy² the same with the column ends. For a W x H px plate seen square on that is 1/√24 = 0.20 px along
each axis whatever its size; for a disc of radius R about 1/√(24 R) (0.035 px at R = 20). Checked against
point-sampled outlines at 300 random sub-pixel positions each: discs of radius 8, 20 and 50 px scatter by
0.049, 0.034 and 0.022 px (the term: 0.049, 0.033, 0.021), boards of 30 x 100 and 80 x 240 px by 0.27 to
0.30 px (their two sides alike offset when the width is a whole number of pixels: 1/√12 = 0.29; 0.20 with
the sides independent), the same boards turned by 3 to 34 degrees by 0.010 to 0.024 px (the term: 0.018 to
0.040). The earlier term took every edge pixel as independent, 0.014 to 0.05 px for those boards: the
endless scene's boards, standing still for seconds at one sub-pixel offset, were 26.6 times their
azimuth 1-σ² off on average.

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
EDGE_PX = 1.0 / np.sqrt(12.0)  # rms error (px) of where the true outline crosses an end pixel
KAPPA = 1.0 / np.sqrt(3.0)  # rms of the unknown share of the hull gap that is the target


def edge_quantisation_px(mask: BoolA) -> tuple[float, float]:
    """The centroid's 1-σ (px, x and y) from the whole-pixel outline: EDGE_PX times the root of the
    weighted sums of the squared distances of the runs of its rows' (columns') end pixels from its
    centroid (straight runs move as one; see the module's docstring), over its area. mask: (h, w) bool,
    any origin. (0, 0) for an empty mask."""
    return outline_sigma_px(mask)[0]


def hull_gap_px(mask: BoolA, kappa: float = KAPPA) -> tuple[float, float]:
    """The centroid's 1-σ (px, x and y) from the mask's hull gap (the pixels of its convex hull, drawn
    through its outline's pixel centres, that are not in it, the hull's own 1-px rim left out): kappa x
    the gap's share of mask and gap x the gap pixels' rms distance from the mask's centroid along each
    axis. mask: (h, w) bool, any origin. (0, 0) for an empty or convex mask."""
    return outline_sigma_px(mask, kappa)[1]


def outline_sigma_px(mask: BoolA, kappa: float = KAPPA) -> tuple[tuple[float, float], tuple[float, float]]:
    """`edge_quantisation_px` and `hull_gap_px` of a mask at once: ((x, y), (x, y)) in px. The mask and its
    hull gap are summed along the columns and rows in one pass (cv2.reduce over the two as channels), their
    centroids and spreads taken from those sums; the runs of the outline's row and column ends are found as
    connected components. About 0.2 ms for a walker's 100 x 45 px mask in the pipeline."""
    bx, by, bw, bh = cv2.boundingRect(mask.view(np.uint8))
    if bw == 0:
        return (0.0, 0.0), (0.0, 0.0)
    m8 = np.ascontiguousarray(mask.view(np.uint8)[by:by + bh, bx:bx + bw])  # the work scales with the box
    contours, _ = cv2.findContours(m8, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    filled = np.zeros_like(m8)
    cv2.fillConvexPoly(filled, cv2.convexHull(np.concatenate(contours)), 1)
    # the hull's own rim left out: a digitised convex outline (a disc) differs from its hull's there
    gap = cv2.subtract(cv2.erode(filled, _CROSS, borderType=cv2.BORDER_CONSTANT, borderValue=0), m8)
    two = cv2.merge([m8, gap])
    cols = cv2.reduce(two, 0, cv2.REDUCE_SUM, dtype=cv2.CV_64F).reshape(-1, 2)  # (w, 2): Σ per column
    rows = cv2.reduce(two, 1, cv2.REDUCE_SUM, dtype=cv2.CV_64F).reshape(-1, 2)  # (h, 2)
    x, y = np.arange(bw, dtype=np.float64), np.arange(bh, dtype=np.float64)
    n, sx, sy, sxx, syy = cols.sum(axis=0), x @ cols, y @ rows, (x * x) @ cols, (y * y) @ rows
    cx, cy = sx[0] / n[0], sy[0] / n[0]
    ex, ey = _end_runs(m8, cx, cy)
    edge_px = (float(EDGE_PX * np.sqrt(ex) / n[0]), float(EDGE_PX * np.sqrt(ey) / n[0]))
    if n[1] == 0:
        return edge_px, (0.0, 0.0)
    # Σ (x - cx)², Σ (y - cy)² of the gap's pixels about the mask's centroid
    vx = max(sxx[1] - 2.0 * cx * sx[1] + cx * cx * n[1], 0.0)
    vy = max(syy[1] - 2.0 * cy * sy[1] + cy * cy * n[1], 0.0)
    share = kappa * n[1] / (n[0] + n[1])
    return edge_px, (float(share * np.sqrt(vx / n[1])), float(share * np.sqrt(vy / n[1])))


def _end_runs(m8: NDArray[np.uint8], cx: float, cy: float) -> tuple[float, float]:
    """Σ_k w_k (x_k - c_x)² over the runs k of the rows' end pixels that lie in one column, and Σ_k w_k
    (y_k - c_y)² over those of the columns' end pixels in one row (px²; see the module's docstring): w_k the
    run's length n_k, or n_k² where it is straight. Two left ends (or two right ends) are never side by
    side in a row, so the runs are the 4-connected components of each side's end pixels; likewise for the
    top and bottom ends."""
    bh, bw = m8.shape
    pad = cv2.copyMakeBorder(m8, 1, 1, 1, 1, cv2.BORDER_CONSTANT, value=0)
    inner = pad[1:-1, 1:-1]
    sums = []
    for axis, c, sides in ((0, cx, (pad[1:-1, :-2], pad[1:-1, 2:])),  # left and right ends: runs down a column
                           (1, cy, (pad[:-2, 1:-1], pad[2:, 1:-1]))):  # top and bottom ends: along a row
        v = 0.0
        for outside in sides:
            ends = cv2.copyMakeBorder(cv2.subtract(inner, outside), 1, 1, 1, 1, cv2.BORDER_CONSTANT, value=0)
            e = np.ascontiguousarray(ends if axis == 0 else ends.T, np.uint8)  # runs down the columns of e
            _, _, stats, centres = cv2.connectedComponentsWithStats(e, connectivity=4)
            k = stats[1:, cv2.CC_STAT_HEIGHT].astype(np.float64)
            d = centres[1:, 0] - (c + 1.0)  # the border of one pixel
            straight = _straight(e, np.asarray(stats[1:], np.int32), extent=bh if axis == 0 else bw)
            v += float(np.where(straight, k * k, k) @ (d * d))
        sums.append(v)
    return sums[0], sums[1]


def _straight(e: NDArray[np.uint8], stats: NDArray[np.int32], extent: int) -> NDArray[np.bool_]:
    """Which runs down the columns of e (end pixels, a zero border around them; stats of their
    components) are straight: at least 2√(2 E) long (E = `extent`, the outline's extent along them: a
    curved outline turns within about 2√R of its radius R) and not a step of a slanted outline's staircase
    (whose neighbouring steps, one column to one side beyond its top and to the other side beyond its
    bottom, carry on the slant)."""
    x, top, n = stats[:, cv2.CC_STAT_LEFT], stats[:, cv2.CC_STAT_TOP], stats[:, cv2.CC_STAT_HEIGHT]
    above = e[top - 1, x + 1].astype(np.int8) - e[top - 1, x - 1].astype(np.int8)  # +1: the step above is right
    below = e[top + n, x + 1].astype(np.int8) - e[top + n, x - 1].astype(np.int8)
    return np.asarray((n >= 2.0 * np.sqrt(2.0 * extent)) & ~((above != 0) & (above == -below)))


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


def outer_runs(mask: BoolA, depth: int = 2) -> tuple[float, float]:
    """The outline's outermost runs (px): the mean count of mask pixels over its first `depth` columns,
    or its last (the larger), and the same over its rows. A strip δ (a pixel or less) wide hidden at a side
    covers about δ times that run: it moves the centroid by δ run (extent / 2) / area, half of δ for a
    rectangle, about an eighth for a disc of radius 15 px (its outer columns 1 and 11 px long: a cap δ
    deep covers about (4/3) √(2 R δ) δ px², 3.2 px² at δ = 0.57, 7.4 px² at δ = 1). Over two columns, not
    the first alone: a rasterised disc often ends in a single pixel. On two-targets:plate (a disc beside a
    nearer crosser, its width's history scattering by 0.57 px with its rounding) azimuth within 1σ 0.762
    -> 0.746, NEES 0.722 -> 0.756 (over one column 0.742, over three 0.754: at the band's edge)."""
    cols, rows = np.flatnonzero(mask.any(axis=0)), np.flatnonzero(mask.any(axis=1))
    if cols.size == 0:
        return 0.0, 0.0
    m = mask[rows[0]:rows[-1] + 1, cols[0]:cols[-1] + 1]
    k = min(depth, m.shape[1]), min(depth, m.shape[0])
    x = max(np.count_nonzero(m[:, :k[0]]), np.count_nonzero(m[:, m.shape[1] - k[0]:])) / k[0]
    y = max(np.count_nonzero(m[:k[1]]), np.count_nonzero(m[m.shape[0] - k[1]:])) / k[1]
    return float(x), float(y)
