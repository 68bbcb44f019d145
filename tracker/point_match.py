"""Disparity of one left point of a rectified pair, voted over shifted windows (tracker.stereo's strip
matching underneath).

One window centred on a point near a depth edge straddles it and locks on one of the two surfaces: on the
Middlebury pairs of ../shared/data/stereo-gt, 40 to 99 % of the single window's errors over 1 px were at
points whose 11 x 11 window spans more than 2 px of true disparity, and of the five-window vote's errors
over 1 px 73 to 100 % per pair were too large (background points given the foreground's disparity).
`match_point` matches nine windows, centred on the point and shifted by `shift` px along x, y and both
(shiftable windows, Bobick and Intille 1999), along the row only (integer search, 1-D refinement,
right-to-left check: cheap). It answers only when the centre window is among a majority (`votes`) that agree
within `tolerance` px and no window lies more than 1 px from them: near a depth edge some shifted windows
see the other surface and disagree, so the point is left unanswered rather than given the wrong surface. A centre
window whose correlation peak is not unique takes part with its best peak (the vote settles it). The
row offset of the right image (real rectifications leave a fraction of a pixel) comes from one 2-D fit
(tracker.stereo_lk.refine_2d; the centre window's, or if that one is rejected the next agreeing window's),
and the answer is the mean of the agreeing windows' disparities refined along that row (their noise
averages, and on a slanted surface the offsets of two mirrored windows cancel when both agree).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.frames import U8
from tracker.stereo import PAD, check_images, match_strip, refine_strip
from tracker.stereo_lk import Fit2D, refine_2d, support_weights

F32 = NDArray[np.float32]


@dataclass(frozen=True)
class WindowOptions:
    """match_window's keyword arguments (see there)."""

    window: int = 11
    min_std: float = 2.0
    min_score: float = 0.5
    uniqueness: float = 0.05
    lr_tolerance: float = 1.5
    max_sigma: float = 0.2
    support_gamma: float = 15.0
    max_row_offset: float = 1.0


_D = WindowOptions()


# The nine windows' offsets from the point, in units of `shift`: the centre, then the four axis shifts
# and the four diagonal ones.
SHIFTS = ((0, 0), (-1, 0), (1, 0), (0, -1), (0, 1), (-1, -1), (1, 1), (1, -1), (-1, 1))
ROW_FITS = 3  # agreeing windows tried, in turn, for the 2-D fit that gives the row offset
NO_UNIQUENESS = -2.0  # a uniqueness margin no correlation peak can fail (scores lie in [-1, 1])


def match_point(left: U8, right: U8, x: float, y: float, max_disparity: int, *, votes: int = 5,
                tolerance: float = 0.5, shift: int = 4, **options: Any) -> float | None:
    """Disparity d (px) of the left point (x, y) in a rectified pair, right x = x - d; None if unreliable.

    The windows: centred on (x, y) and shifted by `shift` px along x, y and both (SHIFTS), each matched
    by match_window's one-dimensional steps and rejections (`options`: its keyword arguments; max_sigma
    applies to the 1-D fit). The agreeing windows: those within `tolerance` px of the window the most
    others are within `tolerance` of (the better score breaks ties). None unless they are at least `votes`
    (by default 5, a majority of the nine), include the centre window, and no other window lies more than
    1 px from that one. The centre window alone is matched again without the uniqueness test if it failed a
    rule (its best peak must then agree with the others). The row offset dy comes from the 2-D fit of the
    centre window, or if it is rejected (match_window's rules) of the next best-scoring agreeing windows
    (ROW_FITS in all); the answer is the mean of the agreeing windows' disparities refined along the row
    y + dy. Raises FrameError / ValueError (one-line message) for bad arguments."""
    if isinstance(votes, bool) or not isinstance(votes, int) or not 1 <= votes <= len(SHIFTS):
        raise ValueError(f"votes must be an integer in 1..{len(SHIFTS)}, got {votes!r}")
    opts = WindowOptions(**options)
    left, right, x, y = _checked(left, right, x, y, max_disparity, opts.window)
    cands = [_coarse(left, right, x + shift * dx, y + shift * dy, max_disparity, opts) for dx, dy in SHIFTS]
    if cands[0] is None:  # the centre's best peak, if only a second one came close: the vote decides
        cands[0] = _coarse(left, right, x, y, max_disparity, replace(opts, uniqueness=NO_UNIQUENESS))
    found = [c for c in cands if c is not None and c.sigma <= opts.max_sigma]
    group = _agreeing(found, votes, tolerance)
    if group is None or cands[0] not in group:
        return None
    order = [group[0], *sorted(group[1:], key=lambda c: -c.score)]  # the centre first, then by score
    fits = ((c, f) for c in order[:ROW_FITS] if (f := _fit_2d(c, right, opts)) is not None)
    lead, fine = next(fits, (None, None))
    if lead is None or fine is None:
        return None
    ds = [d for c in group
          if (d := _refine_on_row(c, right, c.y + fine.dy, fine.d if c is lead else c.d)) is not None
          and abs(d - c.d) <= 0.5]
    return None if not ds else float(np.mean(ds))


def match_window(
    left: U8,
    right: U8,
    x: float,
    y: float,
    max_disparity: int,
    *,
    window: int = _D.window,
    min_std: float = _D.min_std,
    min_score: float = _D.min_score,
    uniqueness: float = _D.uniqueness,
    lr_tolerance: float = _D.lr_tolerance,
    max_sigma: float = _D.max_sigma,
    support_gamma: float = _D.support_gamma,
    max_row_offset: float = _D.max_row_offset,
) -> tuple[float, float] | None:
    """(d, score): disparity d (px) of the left point (x, y) in a rectified pair, right x = x - d, from one
    window centred on the point, and the refined correlation score of the match; None if unreliable.

    left, right: rectified grey uint8 (H, W). window: odd square window side (px), centred on the pixel
    column nearest x and on row y (sub-pixel, interpolated in both images alike); the disparity is assumed
    constant over the window, whose pixels are weighted by their likeness to the centre (adaptive support
    weights exp(-|ΔI| / support_gamma), support_gamma in grey levels). The integer search (weighted
    ZNCC) is refined by tracker.stereo_lk.refine_2d, which fits a row offset of the right image beside
    the disparity (real rectifications leave rows misaligned by a fraction of a pixel).
    The match is rejected (None) when the window or the search strip does not fit in the image (the
    search is clipped at the left edge), the window's grey-level standard deviation is below min_std, the
    correlation peak lies on the border of the search range, its score is below min_score, a second
    correlation peak comes within `uniqueness` of it, the refined disparity's 1-sigma exceeds max_sigma px,
    it moved more than 1 px or the row offset exceeds max_row_offset px, or the right-to-left search from
    the integer search's refined match does not return within lr_tolerance px. Raises FrameError /
    ValueError (one-line message) for bad arguments.
    """
    opts = WindowOptions(window, min_std, min_score, uniqueness, lr_tolerance, max_sigma, support_gamma,
                         max_row_offset)
    left, right, x, y = _checked(left, right, x, y, max_disparity, window)
    return _match_window(left, right, x, y, max_disparity, opts)


def _checked(left: U8, right: U8, x: float, y: float, max_disparity: int, window: int) -> tuple[U8, U8, float, float]:
    """The arguments of match_window checked (FrameError / ValueError with a one-line message)."""
    left, right = check_images(left, right, max_disparity)
    if isinstance(window, bool) or not isinstance(window, int) or window < 3 or window % 2 == 0:
        raise ValueError(f"window must be an odd integer >= 3, got {window!r}")
    x, y = float(x), float(y)
    if not (math.isfinite(x) and math.isfinite(y)):
        raise ValueError(f"point must be finite, got ({x}, {y})")
    return left, right, x, y


@dataclass(frozen=True, eq=False)
class _Coarse:
    """One window after the one-dimensional steps: the template T (n, n) centred on the left (xc, y), its
    support weights w, the right strip's first column xs0 and width ws, the disparity d (px), its 1-sigma
    (px) and the refined correlation score."""

    T: F32
    w: F32
    xc: int
    y: float
    xs0: int
    ws: int
    d: float
    sigma: float
    score: float


def _coarse(left: U8, right: U8, x: float, y: float, max_disparity: int, o: WindowOptions) -> _Coarse | None:
    """The window centred on (x, y): integer weighted-ZNCC search and 1-D refinement (match_strip), then
    the right-to-left check; None if rejected (see match_window)."""
    H, W = left.shape
    h = o.window // 2
    xc = round(x)
    if not (h <= y < H - h - 1 and xc + h + PAD < W):
        return None
    dmax = min(max_disparity, xc - h - PAD)  # clip the search at the image's left edge
    if dmax < 2:
        return None
    T = np.asarray(cv2.getRectSubPix(left, (o.window, o.window), (xc, y), patchType=cv2.CV_32F), np.float32)
    if float(cv2.meanStdDev(T)[1][0, 0]) < o.min_std:
        return None
    xs0 = xc - h - dmax - PAD  # image column of the strip's first column
    ws = dmax + o.window + 2 * PAD
    S = np.asarray(
        cv2.getRectSubPix(right, (ws, o.window), (xs0 + 0.5 * (ws - 1), y), patchType=cv2.CV_32F), np.float32
    )
    w = support_weights(T, o.support_gamma)
    fit = match_strip(T, S, w, dmax + PAD, dmax, o.min_score, o.uniqueness)
    if fit is None or not 0.0 <= fit.d <= max_disparity:
        return None
    if not _lr_consistent(left, right, x, x - fit.d, y, h, max_disparity, o.lr_tolerance):
        return None
    return _Coarse(T, w, xc, y, xs0, ws, fit.d, fit.sigma, fit.score)


def _agreeing(found: list[_Coarse], votes: int, tolerance: float) -> list[_Coarse] | None:
    """The windows within `tolerance` px of the one most others agree with (the better score breaks
    ties); None if they are fewer than `votes` or another window lies over 1 px away."""
    best: tuple[tuple[int, float], _Coarse] | None = None
    for c in found:
        n = sum(abs(e.d - c.d) <= tolerance for e in found)
        if n >= votes and (best is None or (n, c.score) > best[0]):
            best = ((n, c.score), c)
    if best is None:
        return None
    lead = best[1]
    if any(abs(e.d - lead.d) > 1.0 for e in found):
        return None
    return [e for e in found if abs(e.d - lead.d) <= tolerance]


def _fit_2d(c: _Coarse, right: U8, o: WindowOptions) -> Fit2D | None:
    """tracker.stereo_lk.refine_2d from the window's disparity; None if its 1-sigma exceeds max_sigma, it
    moved more than 1 px or the row offset exceeds max_row_offset."""
    fine = refine_2d(c.T, right, c.xc, c.y, c.d, c.w)
    if fine is None or fine.sigma > o.max_sigma or abs(fine.d - c.d) > 1.0 or abs(fine.dy) > o.max_row_offset:
        return None
    return fine


def _match_window(left: U8, right: U8, x: float, y: float, max_disparity: int, o: WindowOptions
                  ) -> tuple[float, float] | None:
    """match_window on checked arguments."""
    c = _coarse(left, right, x, y, max_disparity, o)
    if c is None:
        return None
    fine = _fit_2d(c, right, o)
    if fine is None:
        return None
    d = _refine_on_row(c, right, y + fine.dy, fine.d)
    if d is None or abs(d - fine.d) > 0.5 or not 0.0 <= d <= max_disparity:
        return None
    return d, c.score


def _refine_on_row(c: _Coarse, right: U8, y: float, d0: float) -> float | None:
    """The 1-D Catmull-Rom refinement (not pixel-locked) of the window's disparity from d0 (px) on the
    right strip sampled at row y (a 2-D fit's row offset applied), with the window's weights. The
    disparity (px) or None."""
    T = c.T
    S = np.asarray(cv2.getRectSubPix(right, (c.ws, T.shape[0]), (c.xs0 + 0.5 * (c.ws - 1), y),
                                     patchType=cv2.CV_32F), np.float32)
    offset = c.ws - T.shape[1] - PAD  # strip position p <-> disparity d = offset - p
    p0 = offset - d0
    k = math.floor(p0)
    if not 2 <= k <= c.ws - T.shape[1] - 3:
        return None
    fit = refine_strip(T, S, c.w.ravel().astype(np.float64), p0, k)
    return None if fit is None else offset + fit.d


def _lr_consistent(left: U8, right: U8, x: float, xr: float, y: float, h: int, dmax: int, tol: float) -> bool:
    """Integer right-to-left search from (xr, y); True if it lands within tol px of x."""
    xri, yi = round(xr), round(y)
    W = left.shape[1]
    hi = min(xri + h + dmax, W - 1)
    if xri - h < 0 or hi - xri - h < 2:
        return False
    templ = right[yi - h : yi + h + 1, xri - h : xri + h + 1]
    strip = left[yi - h : yi + h + 1, xri - h : hi + 1]
    r = cv2.matchTemplate(strip, templ, cv2.TM_CCOEFF_NORMED)[0]
    return abs(xri + int(np.argmax(r)) - x) <= tol
