"""What a nearer background below a target says about its bottom side (issue 12 item 1; used by
tracker.visibility.cut_and_skew): an occluder's top edge, which may hide the target's lower part, the ground
the target stands on, or the target's own rounded bottom resting on an occluder's edge.
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

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
