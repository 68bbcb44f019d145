"""What a nearer background below a target says about its bottom side (issue 12 item 1; used by
tracker.visibility.cut_and_skew and tracker.pipeline): an occluder's top edge, which may hide the target's
lower part, the ground the target stands on, or the target's own rounded bottom resting on an occluder's
edge; how tall an occluder below is (`occluder_below`) and how far the centroid would move if the target
went on down unseen to the ground (`unseen_below`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import cv2
import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:  # tracker.visibility uses this module
    from tracker.visibility import VisibilityConfig

BoolA = NDArray[np.bool_]
F32 = NDArray[np.float32]


def lowest_rows(mask: BoolA, by: int, bh: int, bx: int, bw: int) -> NDArray[np.intp]:
    """Each column's lowest mask row over the mask's bounding rectangle (x bx, y by, bw x bh); a column
    with none counts as reaching its bottom."""
    return np.asarray(by + bh - 1 - np.argmax(mask[by:by + bh, bx:bx + bw][::-1], axis=0))


def stepped_below(m8: NDArray[np.uint8], bg: F32, valid: BoolA, ys: NDArray[np.intp], xs: NDArray[np.intp],
                  step_px: float) -> BoolA:
    """For ring pixels (ys, xs) below a mask: whether the background there is nearer by step_px than the
    farthest of the backgrounds behind the mask's lowest four pixels in its column (the nearest column of
    the mask for a ring pixel beside it), both known. An occluder's top edge steps forward from what lies
    behind the target. The ground a target stands on goes on under it, about 0.2 px a row nearer: 1.0 px
    over the six rows from the fourth last to the ring's second, under step_px; and where the learnt map is
    wrong and as near behind the target's lowest rows as below them (the matcher's blotches on the smooth
    ground), the target is seen before it, not hidden by it. Four pixels: the learnt map fattens a nearer
    occluder upwards by a row or two (endless, a bush at 30 px of disparity, 2 rows over the top the
    scene's truth gives it)."""
    cols = np.flatnonzero(m8.any(axis=0))
    low = lowest_rows(m8 > 0, 0, m8.shape[0], 0, m8.shape[1])[cols]  # each mask column's lowest row
    k = np.clip(np.searchsorted(cols, xs), 0, cols.size - 1)
    k = np.where((k > 0) & (np.abs(cols[k - 1] - xs) < np.abs(cols[k] - xs)), k - 1, k)  # the nearest column
    inside_y, inside_x = np.stack([np.maximum(low[k] - j, 0) for j in range(4)]), cols[k]
    inside = np.where(valid[inside_y, inside_x], bg[inside_y, inside_x], np.inf).min(axis=0)
    ok = valid[ys, xs] & np.isfinite(inside)
    return np.asarray(ok & (bg[ys, xs] - inside >= step_px))


def convex_tip(mask: BoolA, hidden: BoolA, solidity: float, tip_rows: float) -> tuple[float, float] | None:
    """Whether the outline's bottom is a convex body's own, not a cut: where the outline is convex (its area at least
    `solidity` of its convex hull's) and its rows narrow downwards, a convex body goes on below its lowest row at
    most until its sides, narrowing at least as fast as they do there, meet: D = w₀ / s rows, w₀ the lowest row's
    pixels and s = (w₂ - w₀) / 2 the narrowing a row over the two rows above it, which must narrow at each step on
    both sides (a cut side's lowest row is often short at one end, and a stray pixel may hang below it). Where D <=
    `tip_rows` that is its tip (a ball resting on a hedge's line seen from 30 m, its bottom rows 5, 8 and 10 px
    wide: D = 2). A smooth outline is a parabola about its lowest point, its width's square falling linearly to 0
    there: the cap below the lowest row is D' = w₀² / ((w₂² - w₀²) / 2) rows deep (0.67 for that ball), its area 2/3
    w₀ D', its centroid 2/5 D' below. The centroid's 1-σ (px, x and y) is the shift that cap would make, divided by
    √3 (anything from none to all of it); None otherwise: the side may go on beyond a cut (a walker's legs behind a
    hedge, rows as wide as those above them; a car's wheels, its outline not convex). And the nearer background must
    touch the outline's bottom only at the tip: it lies within 2 rows below each column's lowest pixel in at most w₁
    + 2 columns, w₁ the second lowest row's pixels (the columns a tip resting on a straight edge spans within those
    rows). An occluder's rounded top (a bush) that hides a board's lower part leaves a visible part that narrows
    downwards too, but the bush follows its whole lower outline, as does a background at about the target's depth,
    against which its lower part may be lost (`cut_sides`). mask, hidden: (h, w) bool, the background that may hide
    the target (nearer, with the columns the right camera does not see because of it, `right_shadow`, or at about
    its depth) over the same box, at least 2 rows below the mask's lowest."""
    m8 = mask.view(np.uint8)
    bx, by, bw, bh = cv2.boundingRect(m8)
    if bh < 3:
        return None
    rows = m8[by:by + bh, bx:bx + bw].sum(axis=1, dtype=np.int64)
    w0, narrowing = float(rows[-1]), (float(rows[-3]) - float(rows[-1])) / 2.0
    sub = m8[by + bh - 3:by + bh, bx:bx + bw] > 0  # the lowest three rows, top down
    first, last = np.argmax(sub, axis=1), bw - 1 - np.argmax(sub[:, ::-1], axis=1)
    # both sides move in at each step: a tip, not a cut side's lowest row short at one end or a stray pixel
    if not (first[0] < first[1] < first[2] and last[0] > last[1] > last[2]) or w0 > tip_rows * narrowing:
        return None
    low = lowest_rows(mask, by, bh, bx, bw)
    cols = np.arange(bx, bx + bw)
    below = np.zeros(bw, bool)
    for k in (1, 2):  # the 2 rows below each column's lowest pixel
        r = low + k
        ok = r < hidden.shape[0]
        below[ok] |= hidden[r[ok], cols[ok]]
    if np.count_nonzero(below) > rows[-2] + 2:
        return None
    box = np.ascontiguousarray(m8[by:by + bh, bx:bx + bw])
    contours, _ = cv2.findContours(box, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    hull = np.zeros_like(box)
    cv2.fillConvexPoly(hull, cv2.convexHull(np.concatenate(contours)), 1)  # its pixels, as the mask's
    area = float(rows.sum())
    if area < solidity * float(np.count_nonzero(hull)):
        return None
    # a smooth outline is a parabola about its lowest point: w² falls linearly to 0 there
    depth = w0 * w0 / ((float(rows[-3]) ** 2 - w0 * w0) / 2.0)
    cap = 2.0 / 3.0 * w0 * depth  # a parabolic segment's area, its centroid 2/5 of its depth from the chord
    mom = cv2.moments(m8, binaryImage=True)
    bottom = np.flatnonzero(m8[by + bh - 1])
    dx = float(bottom.mean()) - mom["m10"] / mom["m00"]  # the cap lies under the lowest row's middle
    dy = by + bh - 0.5 + 0.4 * depth - mom["m01"] / mom["m00"]
    share = cap / (area + cap) / np.sqrt(3.0)
    return abs(share * dx), abs(share * dy)


def occluder_below(mask: BoolA, disparity: float, bg_disparity: F32 | None, bg_valid: BoolA | None,
                   cfg: VisibilityConfig) -> float | None:
    """How tall (px) the nearer background is that hides the target's bottom: in each of the mask's
    columns, the run of rows of a background nearer than the target by nearer_px that starts within
    the 2-px ring below the mask's lowest pixel; the median of those runs over the columns that have one,
    if they are at least min_share of the columns; None otherwise or where the background is not known.
    The hidden part goes on down at most that far (a walker behind a hedge: to its feet behind it), so
    the centroid lies up to half that above the whole target's: a better bound than kappa times the
    visible height where the occluder is much taller than what is seen (endless, frame 884: a walker's
    top 12 px above a hedge reaching 44 px below it, about 24 px more of the walker behind it, off by
    13 px), or much shorter. mask, bg_disparity, bg_valid: (h, w) over the same
    box, padded below (`padded`)."""
    if bg_disparity is None or bg_valid is None:
        return None
    h, _ = mask.shape
    bx, by, bw, bh = cv2.boundingRect(mask.view(np.uint8))
    if bw == 0:
        return None
    low = lowest_rows(mask, by, bh, bx, bw)
    nearer = bg_valid[:, bx:bx + bw] & (bg_disparity[:, bx:bx + bw] > disparity + cfg.nearer_px)
    rows = np.arange(h)[:, None]
    below = (rows > low) & (rows <= low + 3)  # the ring below, where the occluder's top must be
    starts = np.where(below & nearer, rows, h).min(axis=0)  # its first nearer row in each column
    has = starts < h
    if int(np.count_nonzero(has)) < max(cfg.min_share * bw, 1):
        return None
    # the run from there: rows up to the first one below it that is not nearer
    after = (rows >= starts) & ~nearer
    ends = np.where(after, rows, h).min(axis=0)
    runs = ends - starts
    return float(np.median(runs[has]))


def unseen_below(mask: BoolA, disparity: float, bg_disparity: F32 | None, bg_valid: BoolA | None,
                 cfg: VisibilityConfig) -> tuple[float, float]:
    """How far (px, x and y) the centroid would move if the target went on down, unseen, to the ground
    it stands on: in each column, the rows between the mask's lowest pixel and the first background
    below it at about the target's depth or nearer (disparity above d - level_px: where a target on the
    ground meets it), reached with no step over ground_step_px on the way (the ground rising steadily,
    not a far background and then an occluder). The stereo residual cannot tell a target's lowest part
    from the ground at nearly its own depth just behind it, and a temporal model that learnt the target
    while it stood unverified misses it as well (endless, frames 1552-1639: the bottom quarter of a
    plate by the right border lost, elevation off by 1 deg with a 1-σ of 0.004 deg). Rows with the mask
    on both sides (the gap between a walker's legs, seen as background) and gaps longer than the mask's
    height do not count. The offset is the 1-σ: the target may as well end where it is seen.
    mask, bg_disparity, bg_valid: (h, w) over the same padded box (`padded` with `below` the mask's
    height, and the other objects painted in by `with_objects`); None: the background is not known."""
    if bg_disparity is None or bg_valid is None:
        return 0.0, 0.0
    h, w = mask.shape
    bx, by, bw, bh = cv2.boundingRect(mask.view(np.uint8))
    if bw == 0:
        return 0.0, 0.0
    low = lowest_rows(mask, by, bh, bx, bw)  # the work is done over the mask's columns and the rows it may lose
    top, end = int(low.min()) + 1, min(by + 2 * bh + 1, h)
    if top >= end:
        return 0.0, 0.0
    rows = np.arange(top, end)[:, None]
    ground = (bg_disparity[top:end, bx:bx + bw] > disparity - cfg.level_px) & bg_valid[top:end, bx:bx + bw]
    ground &= rows > low
    first = np.argmax(ground, axis=0) + top  # the first row below at about the target's depth, if any
    near = (first > low + 1) & (first - low - 1 <= bh)
    cols = np.flatnonzero(near & ground[first - top, np.arange(bw)])
    if cols.size == 0:  # the common case: seen down to the ground, or no ground below
        return 0.0, 0.0
    low, first, cols = low[cols], first[cols], cols + bx
    # the ground rises steadily to the target (0.2 px a row): no step over ground_step_px from the mask's
    # lowest row to where it meets the target's depth (not a far background, then an occluder below it)
    sub, ok = bg_disparity[:, cols], bg_valid[:, cols]
    step = np.zeros(sub.shape, np.int32)
    step[1:] = (np.abs(np.diff(sub, axis=0)) > cfg.ground_step_px) | ~ok[1:]
    steps = np.cumsum(step, axis=0)
    k = np.arange(cols.size)
    smooth = steps[first, k] == steps[low, k]
    if not smooth.any():
        return 0.0, 0.0
    gap = np.zeros(mask.shape, np.uint8)
    for c, lo, fi in zip(cols[smooth], low[smooth], first[smooth], strict=True):
        gap[lo + 1:fi, c] = 1
    # rows with the mask on both sides of a gap pixel: background seen between the legs
    seen = mask.any(axis=1)
    left = np.where(seen, np.argmax(mask, axis=1), w)[:, None]
    right = np.where(seen, w - 1 - np.argmax(mask[:, ::-1], axis=1), -1)[:, None]
    xs = np.arange(w)[None, :]
    gap[(xs > left) & (xs < right)] = 0
    g, a = cv2.moments(gap, binaryImage=True), cv2.moments(mask.view(np.uint8), binaryImage=True)
    if g["m00"] == 0:
        return 0.0, 0.0
    share = g["m00"] / (a["m00"] + g["m00"])
    return (share * abs(g["m10"] / g["m00"] - a["m10"] / a["m00"]),
            share * abs(g["m01"] / g["m00"] - a["m01"] / a["m00"]))


# feet_at_ground_depth: the outline's lowest share searched below it, how near the background's disparity
# (px) must lie to the target's to hide its edge from eq. (9), and the closing (px, rows x columns)
FEET_SHARE = 0.25
FEET_LEVEL_PX = 1.0
FEET_CLOSE = np.ones((9, 9), np.uint8)


def feet_at_ground_depth(obj: BoolA, keys: BoolA, bg_disparity: F32, bg_valid: BoolA, disparity: float) -> BoolA:
    """The outline `obj` (bool, h x w over a box) with the feet eq. (9) cannot see while the cameras move.
    Where a foot meets the ground at its own depth, the background's disparity D_B equals the foot's d and
    the stereo difference there is zero in both keys but at the foot's edges (pan:body frame 84, rows
    334-347). So below each column's lowest outline pixel, in the outline's lowest FEET_SHARE of rows,
    where |D_B - d| < FEET_LEVEL_PX, the keys' pixels (`keys`: either camera's key mask) are joined to the
    outline by a closing (FEET_CLOSE) and what the closing adds there is kept. Returns `obj` itself when
    nothing is added. On pan:body: against the seen surface, elevation RMSE 0.173 -> 0.142 deg, centroid
    RMSE 2.04 -> 1.80 px (with the head kept, tracker.masks.with_head; see docs/evaluation.md)."""
    rows = np.flatnonzero(obj.any(axis=1))
    if rows.size == 0:
        return obj
    low_from = rows[0] + (1.0 - FEET_SHARE) * (rows[-1] - rows[0] + 1)
    blind = bg_valid & (np.abs(bg_disparity - disparity) < FEET_LEVEL_PX)  # |D_B - d| small: eq. (9) blind
    yy = np.arange(obj.shape[0])[:, None]
    lowest = lowest_rows(obj, 0, obj.shape[0], 0, obj.shape[1])  # a column without any: nothing below it
    zone = blind & (yy >= low_from)
    edges = keys & zone & (yy > lowest[None, :])
    if not edges.any():
        return obj
    closed = cv2.morphologyEx((obj | edges).view(np.uint8), cv2.MORPH_CLOSE, FEET_CLOSE) > 0
    added = closed & zone & ~obj
    return obj | added if added.any() else obj
