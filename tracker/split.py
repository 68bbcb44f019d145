"""Which of several objects at different depths each pixel of a joint outline belongs to.

A farther object seen past a nearer one's edge (a walker's legs below a ball crossing in front) joins the
nearer one's outline: the temporal model (|Γ - g B| > ε) and the masks of eq. (9) say only that pixels
changed, not which object changed them. Its photometry does: a left pixel p of an object at disparity d
shows the same surface point as the right image at p's rectified position shifted by d (paper eq. 1, the
parallel rig after rectification, x_r = x_l - d). Each pixel goes to the candidate disparity with the
smallest windowed absolute difference (winner takes all over the few disparities of the tracks predicted
there, not over the whole range: a local stereo match with a strong prior).

The other way round, one body may be verified as several blobs: its head past the neck's gap in the same
candidate box (same_body), or its two sides of a nearer occluder such as a post in two boxes
(join_occluded); those are joined into one.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.frames import StereoFrame
from tracker.rectify import Rectifier
from tracker.regions import mask_centroid
from tracker.visibility import occluded

if TYPE_CHECKING:
    from tracker.results import Blob

F32 = NDArray[np.float32]
BoolA = NDArray[np.bool_]
Box = tuple[int, int, int, int]

WINDOW_PX = 7  # side of the window the absolute differences are averaged over (px)
# a rival disparity must differ from the object's by this much: 20 % of d is a depth step of about 20 % of
# the range (eq. 2, z = b f / d), more than a walker's own depth (±0.3 m at 3 m); a part of the same body
# predicted apart (a head taken for a track of its own) does not split the body
MIN_GAP_PX = 2.0
MIN_GAP_REL = 0.2


def rival_gap(d: float) -> float:
    """The least disparity difference (px) that tells two surfaces about disparity d apart: max(MIN_GAP_PX,
    MIN_GAP_REL d)."""
    return max(MIN_GAP_PX, MIN_GAP_REL * d)


def right_at(rect: Rectifier, frame: StereoFrame, box: Box, d: float) -> F32:
    """The right image sampled where each left pixel of `box` would be seen at disparity d (px): the raw
    right position of the rectified point (x_rect - d, y_rect), bilinear; (y1 - y0, x1 - x0) float32."""
    ur, vr = rect.right_at(box, d)
    return np.asarray(cv2.remap(frame.right.astype(np.float32), ur, vr, cv2.INTER_LINEAR,
                                borderMode=cv2.BORDER_REPLICATE), np.float32)


def match_cost(rect: Rectifier, frame: StereoFrame, box: Box, d: float) -> F32:
    """Mean |Γ_left(p) - Γ_right(p at disparity d)| over a WINDOW_PX square around each pixel of `box`
    (grey levels, float32 (y1 - y0, x1 - x0))."""
    x0, y0, x1, y1 = box
    left = frame.left[y0:y1, x0:x1].astype(np.float32)
    diff = np.abs(left - right_at(rect, frame, box, d))
    return np.asarray(cv2.blur(diff, (WINDOW_PX, WINDOW_PX), borderType=cv2.BORDER_REFLECT), np.float32)


def own_pixels(rect: Rectifier, frame: StereoFrame, box: Box, obj: BoolA, d: float, others: list[float],
               min_area: int) -> BoolA:
    """The pixels of an object's outline `obj` (box pixels) that match at its disparity d at least as well
    as at every other candidate disparity d_k in `others` (px) at least max(MIN_GAP_PX, MIN_GAP_REL d) away:
    cost(d) <= min_k cost(d_k) (match_cost);
    kept as its largest region, holes filled (where the two match alike, as on a surface without texture,
    the region keeps them). The outline is returned whole when there is no such rival, or when fewer than
    min_area pixels would be left."""
    rivals = [o for o in others if abs(o - d) >= rival_gap(d)]
    if not rivals:
        return obj
    own = match_cost(rect, frame, box, d)
    best_other = np.minimum.reduce([match_cost(rect, frame, box, o) for o in rivals])
    m8 = (obj & (own <= best_other)).astype(np.uint8)
    contours, _ = cv2.findContours(m8, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    if not contours:
        return obj
    kept = np.zeros(m8.shape, np.uint8)
    cv2.drawContours(kept, [max(contours, key=cv2.contourArea)], -1, 1, thickness=cv2.FILLED)
    out = kept > 0
    return out if int(np.count_nonzero(out)) >= min_area else obj


# two regions of one box at one depth are parts of one body when this close: a walker's head and torso
# are a few centimetres apart (the neck), its arms a centimetre from its sides (px: max(PART_GAP_MIN_PX,
# PART_GAP_REL x the larger part's height))
PART_GAP_MIN_PX = 3
PART_GAP_REL = 0.03
# and straight above or below, this much of it: a head over a torso whose outline lost the middle of its
# shoulders (a person's neck and collar close to the background's grey), pan:body frame 62: 7.6 px apart
# at 89 rows, the head then reported as a target of its own with the torso's centroid 50 px below it
PART_STACK_REL = 0.1
# and a region under a tenth of the other's pixels, its middle column within the other's columns, within
# the other's box grown by that many rows: pan:body frame 47, a head 7 rows above a torso's box whose
# pixels under it began 18 rows lower, reported as a target of its own 5.5° above the walker
PART_INSIDE_SHARE = 10


def same_body(a: BoolA, d_a: float, b: BoolA, d_b: float) -> bool:
    """Whether region b (box pixels, disparity d_b px) is a part of the body of region a (d_a): their
    disparities differ by less than the rival gap of own_pixels (max(MIN_GAP_PX, MIN_GAP_REL d)) and b lies
    within max(PART_GAP_MIN_PX, PART_GAP_REL h) px of a, or, the smaller one's middle column within the
    other's columns, as far sideways and s = max(that gap, PART_STACK_REL h) rows above or below it, or,
    the smaller one under 1/PART_INSIDE_SHARE of the other's pixels with its middle column within the
    other's columns, within s rows of the other's rows; h the rows the taller of the two spans, whichever
    was found first (a head verified before its body is as much a part of it as after)."""
    if abs(d_a - d_b) >= rival_gap(max(d_a, d_b)):
        return False
    rows, rows_b = np.flatnonzero(a.any(axis=1)), np.flatnonzero(b.any(axis=1))
    if rows.size == 0 or rows_b.size == 0:
        return False
    h = max(rows[-1] - rows[0] + 1, rows_b[-1] - rows_b[0] + 1)
    gap = max(PART_GAP_MIN_PX, int(round(PART_GAP_REL * h)))
    # straight above or below, further: where the smaller part's middle column lies within the other's
    # columns (a head over its torso, not two people side by side one a little higher in the image); the
    # rectangle holds the disc of radius gap, so one dilation decides
    small, big = (a, b) if np.count_nonzero(a) < np.count_nonzero(b) else (b, a)
    cols, cols_big = np.flatnonzero(small.any(axis=0)), np.flatnonzero(big.any(axis=0))
    rows_s, rows_g = (rows, rows_b) if small is a else (rows_b, rows)
    stack = max(gap, int(round(PART_STACK_REL * h)))
    middle_within = bool(cols_big[0] <= (cols[0] + cols[-1]) / 2.0 <= cols_big[-1])
    if (middle_within and np.count_nonzero(small) * PART_INSIDE_SHARE < np.count_nonzero(big)
            and rows_g[0] - stack <= rows_s[-1] and rows_s[0] <= rows_g[-1] + stack):
        return True  # a small part within the body's rows grown by `stack`
    if middle_within:
        k = np.ones((2 * stack + 1, 2 * gap + 1), np.uint8)
    else:
        k = np.asarray(cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * gap + 1, 2 * gap + 1)), np.uint8)
    return bool(np.any((cv2.dilate(a.view(np.uint8), k) > 0) & b))


# two blobs at one depth are one body seen on both sides of a nearer occluder (a car behind a post, a
# walker's legs past a hedge) when the occluder hides at most this share of the wider blob's width between
# them (px: OCCLUDED_GAP_REL x the union's width) and is nearer by the gap of the verifier's depth test
OCCLUDED_GAP_REL = 0.5
OCCLUDER_SHARE = 0.6  # of the known background pixels in the gap that must be nearer than the body


def occluded_gap(a: Blob, b: Blob, bg_disparity: Callable[[Box], tuple[F32, BoolA]], min_gap: float) -> bool:
    """Whether blobs a (left) and b (right) are one body split by a nearer occluder: their disparities
    within the rival gap (max(MIN_GAP_PX, MIN_GAP_REL d)), their rows overlapping by half the shorter, the
    columns between them at most OCCLUDED_GAP_REL of the union's width, and there, on the shared rows, at
    least OCCLUDER_SHARE of the known background (bg_disparity(box) -> (disparity px, valid)) nearer than
    the body (d_bg > d (1 + min_gap) + 0.5 px, the verifier's test turned round) or in that nearer
    background's shadow (tracker.visibility.right_shadow)."""
    d = max(a.disparity, b.disparity)
    if abs(a.disparity - b.disparity) >= rival_gap(d):
        return False
    ax1 = a.box[0] + int(np.flatnonzero(a.mask.any(axis=0))[-1]) + 1  # first column right of a
    bx0 = b.box[0] + int(np.flatnonzero(b.mask.any(axis=0))[0])
    ra, rb = (blob.box[1] + np.flatnonzero(blob.mask.any(axis=1)) for blob in (a, b))
    y0, y1 = max(ra[0], rb[0]), min(ra[-1], rb[-1]) + 1
    width = max(a.box[2], b.box[2]) - min(a.box[0], b.box[0])
    if bx0 <= ax1 or bx0 - ax1 > OCCLUDED_GAP_REL * width or y1 - y0 < 0.5 * min(ra.size, rb.size):
        return False
    # the occluder and, right of it, the columns the right camera cannot see the body in (d_near - d px
    # wide: verification cannot find it there either): occlusion:body's start-up, the car's two sides of
    # the post 31 px apart, 57 % of the gap the post itself, 71 % with its shadow
    return occluded(*bg_disparity((ax1, y0, bx0, y1)), d, min_gap, 0.5, OCCLUDER_SHARE)


_TOUCH = np.ones((5, 5), np.uint8)  # within 2 px of the nearer background


def hidden_between(body: BoolA, d: float, region: BoolA, bg: tuple[F32, BoolA], min_gap: float,
                   gap_px: float) -> bool:
    """Whether `region` may be a part of `body` (a verified object's mask at disparity d, px; both over one
    box) that a nearer background hides the rest between them from: a walker's leg beside a box that hides
    the rest of its legs and the bottom of its torso (endless:body, frames 273-277, 301-304, 454-462). Both
    lie within 2 px of background nearer than d by the depth-gap test (bg: the map's disparity and where
    it is known over the box, d_bg >= d (1 + min_gap) + gap_px), the region's rows lie between the body's
    top and twice its seen height h below its bottom (a walker seen down to its waist: its legs' 71 rows
    below 66 seen, frame 274), and its columns within h / 2 of the body's."""
    disp, valid = bg
    near = (valid & (disp >= np.float32(d * (1.0 + min_gap) + gap_px))).view(np.uint8)
    rows, cols = np.flatnonzero(body.any(axis=1)), np.flatnonzero(body.any(axis=0))
    r_rows, r_cols = np.flatnonzero(region.any(axis=1)), np.flatnonzero(region.any(axis=0))
    if rows.size == 0 or r_rows.size == 0 or not near.any():
        return False
    h = int(rows[-1] - rows[0] + 1)
    if r_rows[0] < rows[0] or r_rows[-1] > rows[-1] + 2 * h or r_cols[-1] < cols[0] - h // 2 \
            or r_cols[0] > cols[-1] + h // 2:
        return False
    around = cv2.dilate(near, _TOUCH) > 0
    return bool((around & body).any() and (around & region).any())


def join(a: Blob, b: Blob, area_moments: NDArray[np.float64], lead: Blob | None = None) -> Blob:
    """Two blobs as one: masks painted into the union of their boxes, eq. (10) over the union (raw, and
    rectified with each pixel's area from area_moments (H, W, 3) [a x, a y, a]), the disparity, match and
    gain of `lead` (by default the larger blob)."""
    big = lead if lead is not None else (a if a.area >= b.area else b)
    box = _union(a.box, b.box)
    mask = _painted(a, box) | _painted(b, box)
    m8 = mask.view(np.uint8)
    area, c = mask_centroid(m8)
    sx, sy, sa, _ = cv2.mean(area_moments[box[1]:box[3], box[0]:box[2]], mask=m8)
    return replace(big, box=box, mask=mask, area=area, centroid_raw=c + (box[0], box[1]),
                   centroid_rect=np.array([sx / sa, sy / sa]), part_only=False)


def _union(a: Box, b: Box) -> Box:
    return min(a[0], b[0]), min(a[1], b[1]), max(a[2], b[2]), max(a[3], b[3])


def _painted(blob: Blob, box: Box) -> BoolA:
    """The blob's mask painted into `box`, which holds the blob's own box."""
    out = np.zeros((box[3] - box[1], box[2] - box[0]), bool)
    x0, y0, x1, y1 = blob.box
    out[y0 - box[1]:y1 - box[1], x0 - box[0]:x1 - box[0]] = blob.mask
    return out


def _join_linked(blobs: list[Blob], linked: Callable[[Blob, Blob], bool], area_moments: NDArray[np.float64]
                 ) -> list[Blob]:
    """The blobs with each pair `linked` says are one object joined in the first's place (join, the larger's
    disparity); the others keep their order."""
    out = list(blobs)
    k = 0
    while k + 1 < len(out):
        j = next((j for j in range(k + 1, len(out)) if linked(out[k], out[j])), None)
        if j is None:
            k += 1
            continue
        out[k] = join(out[k], out.pop(j), area_moments)
    return out


def join_occluded(blobs: list[Blob], bg_disparity: Callable[[Box], tuple[F32, BoolA]], min_gap: float,
                  area_moments: NDArray[np.float64]) -> list[Blob]:
    """The blobs with each pair split by a nearer occluder (occluded_gap) joined in the first's place; the
    others keep their order."""
    return _join_linked(blobs, lambda a, b: occluded_gap(*_left_right(a, b), bg_disparity, min_gap), area_moments)


def _left_right(a: Blob, b: Blob) -> tuple[Blob, Blob]:
    return (a, b) if a.centroid_raw[0] <= b.centroid_raw[0] else (b, a)


def join_parts(blobs: list[Blob], area_moments: NDArray[np.float64]) -> list[Blob]:
    """The blobs with the parts of one body verified from different candidate boxes joined (a walker close
    to a wall, whose candidate stage splits it at the waist or the neck): each pair same_body links, over
    the union of their boxes, joined in the first's place with the larger's disparity (join); the others
    keep their order. The rule tracker.verify applies to the regions of one box, applied across boxes."""
    return _join_linked(blobs, _parts_of_one, area_moments)


def _parts_of_one(a: Blob, b: Blob) -> bool:
    """same_body for blobs of different boxes: both masks painted into the union of the boxes, the larger
    blob as the body; boxes farther apart than any part gap (from the taller box's rows) are not compared."""
    if a.area < b.area:
        a, b = b, a
    tall = max(a.mask.shape[0], b.mask.shape[0])  # at least the taller row span, which same_body takes
    gap = max(PART_GAP_MIN_PX, int(round(PART_GAP_REL * tall))) + 1
    stack = max(gap, int(round(PART_STACK_REL * tall)) + 1)
    if (b.box[0] > a.box[2] + gap or a.box[0] > b.box[2] + gap or b.box[1] > a.box[3] + stack
            or a.box[1] > b.box[3] + stack):
        return False
    box = _union(a.box, b.box)
    return same_body(_painted(a, box), a.disparity, _painted(b, box), b.disparity)
