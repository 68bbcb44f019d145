"""Rectified strips of both images over a region's rows, and the region's disparity matched on them
(tracker.verify)."""

from __future__ import annotations

from dataclasses import dataclass, replace

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.rectify import Rectifier
from tracker.solid_prior import SolidPrior
from tracker.stereo import RegionMatch, match_region, refine_region, zncc_weighted

U8 = NDArray[np.uint8]
BoolA = NDArray[np.bool_]
Box = tuple[int, int, int, int]
CORE = np.ones((3, 3), np.uint8)  # the erosion that shrinks an outline to its core (Strips.core)
# weighted ZNCC a region's match needs: a whole object scores 0.95-0.99; a sliver beside an occluder that
# catches the occluder's edge scores lower and would give a wrong disparity
MIN_SCORE = 0.8
# how much worse (ZNCC) than its best about it the whole region, outline included, may match at a small
# region's disparity (`outline_agrees`)
AGREE_TOL = 0.2
_AGREE_SPAN = 4  # px either side of the disparity over which the whole region's best is taken
# the weighted ZNCC a small region's whole mask needs to give its disparity (`whole_match`): its outline
# mixes the object with the background beside it (a far plate: 0.60 where its core scores 0.88)
WHOLE_MIN_SCORE = 0.6
# how much better (ZNCC) than anywhere else in the span, more than 1 px from it, the whole region must
# match at its best for `whole_match` to take it: a sliver beside a post scored 0.69 at 22 px and 0.61 at
# 16 px (occlusion:plate frame 91, the truth 14.9 px)
WHOLE_MARGIN = 0.1


MATCH_HALF = (24, 16)  # half width and height (px) of the largest window matched (first_window: not a person's)
_WHOLE = (1 << 16, 1 << 16)  # a half window that holds any region: its whole outline
_PERSON = SolidPrior()  # what counts as a person's outline (SolidPrior.upright)


def first_window(obj: BoolA) -> tuple[int, int]:
    """The half window (px, width and height) a region's disparity is matched on first: an upright region's
    (a person's, SolidPrior.upright: at least 1.5 times as high as wide) whole outline, any other's central
    MATCH_HALF. The parts of a person lie at depths within a few centimetres of each other, but the
    disparity matched on a window of them is off the whole seen surface's by an error that belongs to the
    pixels matched (their texture and the interpolation): on endless:body frame 1846, a walker standing at
    14 m whose true disparity varies by 0.02 px over the body, the central 29 x 32 px of its target pixels
    matched 0.134 px off its seen surface's mean point, all of them 0.003 px. `tmeye eval --all`, matching a
    person's whole outline (and its parts, tracker.disparity_sigma, over it): azimuth / elevation RMSE
    against the seen surface walk:body 0.061 -> 0.054° / 0.218 -> 0.195°, illumination 0.064 -> 0.055 /
    0.229 -> 0.191, foliage 0.068 -> 0.055 / 0.221 -> 0.189 (the rim, tracker.rim, is recovered about the
    better disparity); range RMSE walk 0.094 -> 0.087 m, illumination 0.098 -> 0.088, foliage 0.099 -> 0.091,
    two-targets 0.099 -> 0.091, pan 0.077 -> 0.074, endless 0.393 -> 0.388. The whole of every region
    instead made the car's (a side whose disparity varies across it) azimuth 0.317 -> 0.785° and the near
    ball's elevation 0.015 -> 0.042° (approach:body, 0.9-1.3 m): they keep the central window."""
    return _WHOLE if whole_outline(obj) else MATCH_HALF


def whole_outline(obj: BoolA) -> bool:
    """Whether a region's disparity is matched over its whole outline (first_window): it is upright."""
    _, _, w, h = cv2.boundingRect(obj.view(np.uint8))
    return _PERSON.upright(float(w), float(h))


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
        core = np.asarray(cv2.erode((wgt > 0.99).astype(np.uint8), CORE), np.uint8)
        whole = (wgt > 0.5).astype(np.uint8)
        if int(np.count_nonzero(core)) < 8:
            core = whole
        return core, whole

    def match(self, region: BoolA, d0: float | None, radius: int, whole_ok: bool = False) -> RegionMatch | None:
        """One disparity for the region (raw-left mask with its box's origin), mask-weighted, shrunk by
        about a pixel so that no background next to the outline enters the match. A small region, whose
        shrunk core keeps under half its pixels (a far head and shoulders, about 100 px), is matched on
        little more than its inside, and a smooth inside may match best far off; its match stands only
        where the whole region, outline included, agrees (`outline_agrees`). endless:body, a walker's head
        and shoulders over a hedge at 27 m: frames 872-878 and 889-892 matched 2.0 to 2.8 px too near
        (range up to 7.6 m short; 879-888 were not matched); with the check 872 and 877-889 were not
        matched, 873-876 still 2.0 to 2.3 px near (the whole region scores 0.20 below its best there, at
        the margin). Where the core's match disagrees or fails, the whole region of a tracked object
        (whole_ok: a track's prediction d0, not a new object's coarse search) gives the disparity itself
        (`whole_match`, about the core's match or d0; a new object's whole region took a shadow's edge on
        a wall for an object 3 px before it, tests/test_temporal.py): the track then holds through frames
        869-887 at 6.2 to 6.7 px (the truth 6.5 to 6.6), one frame lost (888) where 17 were, 869-872 and
        877-889, with the check alone and the code of the day. Range RMSE 0.616 -> 0.501 m with the check
        (0.497 m later that day), 0.434 m with the whole region's match; detection 0.959 -> 0.958 -> 0.976."""
        core, whole = self._core_and_whole(region)
        fit = None
        if d0 is not None:  # a good prior: refine from it, search around it only if that fails
            fit = refine_region(self.left, self.right, core, self.off, 0, d0, min_score=MIN_SCORE)
        if fit is None:
            fit = match_region(self.left, self.right, core, self.off, 0, self.d_hi, d0, search_radius=radius,
                               min_score=MIN_SCORE)
        if 2 * int(np.count_nonzero(core)) >= int(np.count_nonzero(whole)):
            return fit
        around = fit.disparity if fit is not None else d0
        if around is None or (fit is None and not whole_ok):
            return None
        ds, scores = _whole_scores(self.left, self.right, whole, self.off, around)  # once, for both tests
        if fit is not None and _agrees(ds, scores, fit.disparity, AGREE_TOL):
            return fit
        peak = _peak_match(self.left, self.right, whole, self.off, ds, scores) if whole_ok else None
        return peak if peak is None or d0 is None else disputed(peak, d0)


def disputed(peak: RegionMatch, d0: float) -> RegionMatch:
    """A whole region's peak (`whole_match`) taken where its core's match failed or disagreed, its 1-σ
    widened by half its distance from the track's prediction d0 (px): the two disagree and neither is
    known right, the peak being the outline's edges, which may be a nearer occluder's beside a sliver
    (endless:body seed 2, frames 3445-3454: a walker's 10-20 px sliver beside a post took the whole
    region's peak at 13.4-14.2 px against a prediction of 10.9-11.8 and a truth of 11.4, its 1-σ 0.09-0.16
    px; range |z| 9 to 15), or the track's prediction having drifted while it coasted (a head over a hedge
    at 26 m, seed 1, frames 2758-2788: the peak within 0.1 px of the truth, the prediction 1.3-2.2 px off)."""
    return replace(peak, sigma=float(np.hypot(peak.sigma, 0.5 * abs(peak.disparity - d0))))


def _whole_scores(left: U8, right: U8, whole: U8, off: int, d: float
                  ) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """The whole region's weighted ZNCC at the whole disparities from floor(d) - 4 to ceil(d) + 4 that the
    strips hold (`outline_agrees`): the disparities and their scores."""
    n = whole.shape[1]
    ds = np.arange(max(int(np.floor(d)) - _AGREE_SPAN, 0), int(np.ceil(d)) + _AGREE_SPAN + 1)
    ds = ds[(off - ds >= 0) & (off - ds + n <= right.shape[1])]  # right columns off - d .. off - d + n
    if ds.size < 2:
        return ds, np.zeros(0)
    j0, j1 = off - int(ds[-1]), off - int(ds[0])  # the right strip's columns, from the largest d
    r = zncc_weighted(right[:, j0:j1 + n].astype(np.float32), left[:, off:off + n].astype(np.float32),
                      whole.astype(np.float32))  # r[j - j0]: disparity off - j
    return ds, np.asarray(r[off - ds - j0], np.float64)


def whole_match(left: U8, right: U8, whole: U8, off: int, d: float) -> RegionMatch | None:
    """A small region's disparity from the whole region, outline included, where its core's match
    disagrees with it or fails: the whole region's best weighted ZNCC over the whole disparities from
    floor(d) - 4 to ceil(d) + 4 (d: the core's match, or the track's prediction), refined about it
    (tracker.stereo.refine_region, which needs ceil(d) + 5 columns of the right strip left of the window:
    a peak nearer the strips' end gives None), scoring at least WHOLE_MIN_SCORE and WHOLE_MARGIN above
    every disparity more than 1 px from it. None where the best lies at the span's end or nothing in the
    span lies that far from it. The outline's pixels mix the object with the background beside it and
    lower the score, but they carry the region's edges, which a far head's smooth inside lacks
    (endless:body frame 874: the core of 27 px best at 9 px, the whole region of 101 px best at 6 px,
    0.70, the truth 6.57 px). The span is wider than a far track's search radius (1 px at 27 m,
    RegionMatcher.search_radius): a track that took a wrong disparity is 2 px off (8.7 px there) and must be
    able to come back; the margin keeps out the hedge's or a post's second peak that radius guards against."""
    return _peak_match(left, right, whole, off, *_whole_scores(left, right, whole, off, d))


def _peak_match(left: U8, right: U8, whole: U8, off: int, ds: NDArray[np.int64], scores: NDArray[np.float64]
                ) -> RegionMatch | None:
    """`whole_match` on the whole region's scores at the disparities ds (`_whole_scores`)."""
    if ds.size < 3:
        return None
    k = int(np.argmax(scores))
    if k == 0 or k == ds.size - 1:
        return None
    away = np.abs(np.arange(ds.size) - k) > 1
    if not away.any() or float(scores[k] - scores[away].max()) < WHOLE_MARGIN:
        return None  # nothing to stand out from, or no peak that does
    return refine_region(left, right, whole, off, 0, float(ds[k]), min_score=WHOLE_MIN_SCORE)


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
    return _agrees(*_whole_scores(left, right, whole, off, d), d, tol)


def _agrees(ds: NDArray[np.int64], scores: NDArray[np.float64], d: float, tol: float) -> bool:
    """`outline_agrees` on the whole region's scores at the disparities ds (`_whole_scores`)."""
    if ds.size < 2:
        return False
    return float(np.interp(d, ds, scores)) >= float(scores.max()) - tol
