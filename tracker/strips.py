"""Rectified strips of both images over a region's rows, and the region's disparity matched on them
(tracker.verify)."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.rectify import Rectifier
from tracker.stereo import RegionMatch, match_region, refine_region

U8 = NDArray[np.uint8]
BoolA = NDArray[np.bool_]
Box = tuple[int, int, int, int]
_CORE = np.ones((3, 3), np.uint8)
# weighted ZNCC a region's match needs: a whole object scores 0.95-0.99; a sliver beside an occluder that
# catches the occluder's edge scores lower and would give a wrong disparity
MIN_SCORE = 0.8


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
        x0, y0 = self.origin
        rx0, ry0, rx1, ry1 = self.window
        mx, my = self.rect.maps[0]
        mmx = mx[ry0:ry1, rx0:rx1] - np.float32(x0)
        mmy = my[ry0:ry1, rx0:rx1] - np.float32(y0)
        wgt = cv2.remap(region.astype(np.float32), mmx, mmy, cv2.INTER_LINEAR,
                        borderMode=cv2.BORDER_CONSTANT, borderValue=0.0)
        core = np.asarray(cv2.erode((wgt > 0.99).astype(np.uint8), _CORE), np.uint8)
        if int(np.count_nonzero(core)) < 8:
            core = (wgt > 0.5).astype(np.uint8)
        return core

    def match(self, region: BoolA, d0: float | None, radius: int) -> RegionMatch | None:
        """One disparity for the region (raw-left mask with its box's origin), mask-weighted, shrunk by
        about a pixel so that no background next to the outline enters the match."""
        core = self.core(region)
        if d0 is not None:  # a good prior: refine from it, search around it only if that fails
            fit = refine_region(self.left, self.right, core, self.off, 0, d0, min_score=MIN_SCORE)
            if fit is not None:
                return fit
        return match_region(self.left, self.right, core, self.off, 0, self.d_hi, d0, search_radius=radius,
                            min_score=MIN_SCORE)
