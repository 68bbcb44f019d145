"""Rectified strips of both images over a region's rows, and the region's disparity matched on them
(tracker.verify)."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.rectify import Rectifier
from tracker.stereo import RegionMatch, match_region, refine_region, zncc_weighted

U8 = NDArray[np.uint8]
BoolA = NDArray[np.bool_]
Box = tuple[int, int, int, int]
_CORE = np.ones((3, 3), np.uint8)
# weighted ZNCC a region's match needs: a whole object scores 0.95-0.99; a sliver beside an occluder that
# catches the occluder's edge scores lower and would give a wrong disparity
MIN_SCORE = 0.8
# how much worse (ZNCC) than its best about it the whole region, outline included, may match at a small
# region's disparity (`outline_agrees`)
AGREE_TOL = 0.2
_AGREE_SPAN = 4  # px either side of the disparity over which the whole region's best is taken


@dataclass(frozen=True)
class Strips:
    """Rectified strips of both images over the rows of a region: the region's rectified window is
    (rx0, ry0, rx1, ry1); it starts at column `off` of the strips; disparities up to d_hi fit."""

    rect: Rectifier
    origin: tuple[int, int]
    window: Box
    left: U8
    right: U8
    off: int
    d_hi: int
    clipped: bool = False  # the image's left edge cut the search range short

    def core(self, region: BoolA) -> U8:
        """The region (raw-left mask with its box's origin) over the rectified window, (h, n) uint8 0/1,
        shrunk by about a pixel so that no background next to the outline enters a match."""
        return self._core_and_whole(region)[0]

    def _core_and_whole(self, region: BoolA) -> tuple[U8, U8]:
        x0, y0 = self.origin
        rx0, ry0, rx1, ry1 = self.window
        mx, my = self.rect.maps[0]
        mmx = mx[ry0:ry1, rx0:rx1] - np.float32(x0)
        mmy = my[ry0:ry1, rx0:rx1] - np.float32(y0)
        wgt = cv2.remap(region.astype(np.float32), mmx, mmy, cv2.INTER_LINEAR,
                        borderMode=cv2.BORDER_CONSTANT, borderValue=0.0)
        core = np.asarray(cv2.erode((wgt > 0.99).astype(np.uint8), _CORE), np.uint8)
        whole = (wgt > 0.5).astype(np.uint8)
        if int(np.count_nonzero(core)) < 8:
            core = whole
        return core, whole

    def match(self, region: BoolA, d0: float | None, radius: int) -> RegionMatch | None:
        """One disparity for the region (raw-left mask with its box's origin), mask-weighted, shrunk by
        about a pixel so that no background next to the outline enters the match. A small region, whose
        shrunk core keeps under half its pixels (a far head and shoulders, about 100 px), is matched on
        little more than its inside, and a smooth inside may match best far off; its match stands only
        where the whole region, outline included, agrees (`outline_agrees`). endless:body, a walker's head
        and shoulders over a hedge at 27 m: frames 872-878 and 889-892 matched 2.0 to 2.8 px too near
        (range up to 7.6 m short; 879-888 were not matched); now 872 and 877-889 are not matched, 890-892
        are 0.5 to 0.7 px near and 873-876 still 2.0 to 2.3 px (the whole region scores 0.20 below its
        best there, at the margin). Range RMSE 0.616 -> 0.501 m, detection 0.959 -> 0.958; with AGREE_TOL
        0.15 they are 0.438 m and 0.951."""
        core, whole = self._core_and_whole(region)
        fit = None
        if d0 is not None:  # a good prior: refine from it, search around it only if that fails
            fit = refine_region(self.left, self.right, core, self.off, 0, d0, min_score=MIN_SCORE)
        if fit is None:
            fit = match_region(self.left, self.right, core, self.off, 0, self.d_hi, d0, search_radius=radius,
                               min_score=MIN_SCORE)
        if fit is None or 2 * int(np.count_nonzero(core)) >= int(np.count_nonzero(whole)):
            return fit
        return fit if outline_agrees(self.left, self.right, whole, self.off, fit.disparity) else None


def outline_agrees(left: U8, right: U8, whole: U8, off: int, d: float, tol: float = AGREE_TOL) -> bool:
    """Whether the whole region `whole` ((h, n) 0/1 over the left strip's columns off .. off + n, its
    outline's pixels included) matches at disparity d (px) within `tol` of its best weighted ZNCC over
    the whole disparities from floor(d) - 4 to ceil(d) + 4 that the strips hold. left, right: (h, m)
    strips, right column off - d seeing what left column off sees at disparity d. The outline's pixels
    mix the object with the background beside it, so the whole region scores lower than its core where
    both are right (a far plate: 0.60 against 0.88 at 6.4 px); but where the core's best lies far from
    the whole region's, the whole region's edges, which the core leaves out, say the core matched its
    smooth inside wrongly (the head above: the core 0.92 at 8.9 px, the whole region 0.47 there and 0.73
    at 6). False where fewer than two disparities can be tried (nothing to compare with)."""
    n = whole.shape[1]
    ds = np.arange(max(int(np.floor(d)) - _AGREE_SPAN, 0), int(np.ceil(d)) + _AGREE_SPAN + 1)
    ds = ds[(off - ds >= 0) & (off - ds + n <= right.shape[1])]  # right columns off - d .. off - d + n
    if ds.size < 2:
        return False
    j0, j1 = off - int(ds[-1]), off - int(ds[0])  # the right strip's columns, from the largest d
    r = zncc_weighted(right[:, j0:j1 + n].astype(np.float32), left[:, off:off + n].astype(np.float32),
                      whole.astype(np.float32))  # r[j - j0]: disparity off - j
    scores = r[off - ds - j0]
    return float(np.interp(d, ds, scores)) >= float(scores.max()) - tol
