"""What may be hidden of a target seen in part (issue 12 item 1): the centroid's extra 1-σ where the image's
border, another object or a nearer background cuts it, for tracker.pipeline's SigmaTerms."""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.bgdepth import CorrespondenceMap
from tracker.bottom_edge import occluder_below, unseen_below
from tracker.detect import Box
from tracker.results import Blob
from tracker.solid_prior import SolidPrior
from tracker.visibility import VisibilityConfig, cut_sigma_px, cuts, painted, with_objects

BoolA = NDArray[np.bool_]


def partly_seen(b: Blob, others: list[tuple[Box, BoolA, float]], upright: bool,
                ring: tuple[BoolA, Box, CorrespondenceMap], size: tuple[int, int], cfg: VisibilityConfig,
                person: tuple[SolidPrior | None, float], level_from: float | None = None
                ) -> tuple[bool, tuple[float, float], tuple[bool, bool]]:
    """Whether a nearer background or the image's bottom edge cuts the blob's bottom and nothing its top (a
    person near the cameras, its legs past the edge, is then placed from its top: walk:body's walker at 3 m
    had an elevation 1-σ of 9.7°, the cut's kappa term, for errors of 0.73° rms, 0.39° from its top), and
    the centroid's extra 1-σ (px, x and y) where the blob is cut by the image border, by another object found this
    frame (others: box, mask, disparity) or by a nearer background (the cameras moving, too: pan:body
    elevation within 1σ 0.54 -> 0.67), with the move across the cut sides; and, in quadrature, the offset
    of the rows down to the ground where the blob's lowest part may be lost against it
    (tracker.visibility). All of it is what may be hidden: SigmaTerms.cut_px; and whether the width
    and the height were seen whole (SigmaTerms.seen_whole). An upright body (`upright`: a person) whose bottom a
    nearer background hides, its top seen, has no move along x across that bottom: `cuts` takes the
    hidden part to go on beyond the occluder's edge away from the visible centroid, but a person's
    hidden legs stand under what is seen. On the frames such a body is placed from its top (walk,
    foliage, two-targets, endless), that move made the centroid's x term 0.45 to 1.17 px (medians)
    for azimuth errors of 0.15 to 0.27 px (medians); 90 to 98 % of those frames were within 1σ. One cut at
    a side: y's term holds its shortfall of a person's stature / √12 (endless:body, frames 1546-1548).
    An upright body under part_share of a person's stature with no cut found on an axis: the rest of the
    person lies anywhere about it (SolidPrior.unseen_rest_px; endless:body with seed 1, frames 2512-2585, a
    walker behind a post seen as a sliver beside it, the map beside it far: azimuth errors of 1.3° against a
    1-σ of 0.009°), and that axis is not seen whole.
    size: the image's (width, height); person: the SolidPrior (None: none) and the baseline (m);
    level_from: tracker.pipeline's `_level_from`."""
    mask, box, cm = ring  # the blob's mask over its box grown (`padded`), the correspondences there
    disp, valid = with_objects(cm.disparity, cm.valid, box, others)
    n = min(b.box[3] + 2, size[1]) - box[1]  # cut_sides: the 2-px ring below, not the ground
    objects = painted(box, others)
    seen = cuts(mask[:n], (box[0], box[1], box[2], box[1] + n), size, b.disparity,
                None if disp is None else disp[:n], None if valid is None else valid[:n], cfg,
                None if objects is None else objects[:n], level_from)
    sx, sy = seen.skew
    tall = occluder_below(mask, b.disparity, disp, valid, cfg) if seen.bottom_by_background else None
    px, py = cut_sigma_px(b.mask, seen, cfg, tall)
    ux, uy = unseen_below(mask, b.disparity, disp, valid, cfg)
    left, right, top, bottom = seen.sides
    hidden_below = bottom and not top  # by a nearer background or past the image's bottom edge (`cuts`' sides)
    if hidden_below and upright:  # a person's hidden lower part stands under what is seen
        sx = 0.0
    if upright and seen.hidden_from is not None:  # but a leg seen beside an occluder stands to one side
        sx = float(np.hypot(sx, legs_aside_px(mask[:n], seen.hidden_from)))
    solid, baseline_m = person
    _, _, w, h = cv2.boundingRect(b.mask.view(np.uint8))  # the outline's extent (px)
    if upright and (left or right) and solid is not None:  # the rest above or below it
        sy = float(np.hypot(sy, solid.short_of_stature_px(float(h), b.disparity, baseline_m) / 12**0.5))
    whole = (not (left or right) and ux == 0.0, not (top or bottom) and uy == 0.0)
    if upright and solid is not None:  # a person seen in part where no cut was found
        rx, ry = solid.unseen_rest_px(float(w), float(h), b.disparity, baseline_m, (not whole[0], not whole[1]))
        ux, uy = ux if rx is None else rx, uy if ry is None else ry
        whole = (whole[0] and rx is None, whole[1] and ry is None)
    cut = (float(np.sqrt(px * px + sx * sx + ux * ux)), float(np.sqrt(py * py + sy * sy + uy * uy)))
    return hidden_below, cut, whole


def legs_aside_px(mask: BoolA, hidden_from: int) -> float:
    """How far (px) a person's centroid along x may lie off its centre where a nearer background hides its
    lower part from row `hidden_from` of `mask` (its outline, bool (h, w)) down and some of what lies there is
    seen beside the occluder (a leg past its edge): its hidden legs stand under what is seen above, so the
    pixels seen below move the centroid by their share of the whole times their mean's offset along x from
    the mean of the rows above, n_low |x̄_low - x̄_up| / n. 0 where nothing shows below or above."""
    ys, xs = np.nonzero(mask)
    low = ys >= hidden_from
    n_low = int(np.count_nonzero(low))
    if n_low == 0 or n_low == xs.size:
        return 0.0
    return n_low * abs(float(xs[low].mean()) - float(xs[~low].mean())) / xs.size


def speck_rest(b: Blob, solid: SolidPrior, baseline_m: float, cut: tuple[float, float],
               whole: tuple[bool, bool]) -> tuple[tuple[float, float], tuple[bool, bool]]:
    """The cut terms (px, x and y; `partly_seen`'s) and seen_whole of a blob whose outline is a speck
    (SolidPrior.speck: smaller along both axes than any whole body the prior is for): the rest of the body
    may lie anywhere about it, as for a person's fragment (SolidPrior.unseen_rest_px), whether or not a cut
    was found (a cut side's term, a share of the speck's own extent, describes the same hidden part: the
    larger holds); neither axis seen whole. Others unchanged."""
    _, _, w, h = cv2.boundingRect(b.mask.view(np.uint8))
    if not solid.speck(float(w), float(h), b.disparity, baseline_m):
        return cut, whole
    rx, ry = solid.unseen_rest_px(float(w), float(h), b.disparity, baseline_m, (False, False))
    return (max(cut[0], rx or 0.0), max(cut[1], ry or 0.0)), (False, False)
