"""Disparity of one left point of a rectified pair, voted over shifted windows (tracker.stereo's strip
matching underneath).

One window centred on a point near a depth edge straddles it and locks on one of the two surfaces: on the
Middlebury pairs of ../shared/data/stereo-gt, 40 to 99 % of the single window's errors over 1 px were at
points whose 11 x 11 window spans more than 2 px of true disparity. Windows shifted by `shift` px left,
right, up and down keep the point near one of their borders, so that some lie on the point's own surface
(shiftable windows, Bobick and Intille 1999). `match_point` answers with the disparity of the window the
most others agree with (within `tolerance` px; the better score breaks ties), and only when at least
`votes` of the five windows agree, which also rejects points whose windows disagree.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.frames import U8
from tracker.stereo import PAD, check_images, match_strip, refine_strip
from tracker.stereo_lk import refine_2d, support_weights

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


def match_point(left: U8, right: U8, x: float, y: float, max_disparity: int, *, votes: int = 3,
                tolerance: float = 0.5, shift: int = 4, **options: Any) -> float | None:
    """Disparity d (px) of the left point (x, y) in a rectified pair, right x = x - d; None if unreliable.

    The windows: centred on (x, y) and shifted by `shift` px in x and in y, each matched by match_window
    (`options`: its keyword arguments, the window side and the rejection thresholds). The
    answer is the d of the window with the most others within `tolerance` px of it, if they are at least
    `votes` (itself included). Raises FrameError / ValueError (one-line message) for bad arguments."""
    if isinstance(votes, bool) or not isinstance(votes, int) or not 1 <= votes <= 5:
        raise ValueError(f"votes must be an integer in 1..5, got {votes!r}")
    opts = WindowOptions(**options)
    left, right, x, y = _checked(left, right, x, y, max_disparity, opts.window)
    answers = [m for dx, dy in ((0, 0), (-shift, 0), (shift, 0), (0, -shift), (0, shift))
               if (m := _match_window(left, right, x + dx, y + dy, max_disparity, opts)) is not None]
    best: tuple[tuple[int, float], float] | None = None
    for d, score in answers:
        n = sum(abs(e - d) <= tolerance for e, _ in answers)
        if n >= votes and (best is None or (n, score) > best[0]):
            best = ((n, score), d)
    return None if best is None else best[1]


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
    it moved more than 1 px or the row offset exceeds max_row_offset px, or the right-to-left search does
    not return within lr_tolerance px. Raises FrameError / ValueError (one-line message) for bad arguments.
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


def _match_window(left: U8, right: U8, x: float, y: float, max_disparity: int, o: WindowOptions
                  ) -> tuple[float, float] | None:
    """match_window on checked arguments."""
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
    if fit is None:
        return None
    fine = refine_2d(T, right, xc, y, fit.d, w)
    if fine is None or fine.sigma > o.max_sigma or abs(fine.d - fit.d) > 1.0 or abs(fine.dy) > o.max_row_offset:
        return None
    d = _refine_on_row(T, right, w, xs0, ws, y + fine.dy, dmax + PAD - fine.d)
    if d is None or abs(d - fine.d) > 0.5 or not 0.0 <= d <= max_disparity:
        return None
    if not _lr_consistent(left, right, x, x - d, y, h, max_disparity, o.lr_tolerance):
        return None
    return d, fit.score


def _refine_on_row(T: F32, right: U8, w: F32, xs0: int, ws: int, y: float, p0: float) -> float | None:
    """The 1-D Catmull-Rom refinement (not pixel-locked) on the right strip sampled at row y (the
    2-D fit's row offset applied) from strip position p0, with the same weights as the 2-D fit.
    Returns the disparity (px) or None."""
    S = np.asarray(cv2.getRectSubPix(right, (ws, T.shape[0]), (xs0 + 0.5 * (ws - 1), y), patchType=cv2.CV_32F),
                   np.float32)
    k = math.floor(p0)
    if not 2 <= k <= ws - T.shape[1] - 3:
        return None
    fit = refine_strip(T, S, w.ravel().astype(np.float64), p0, k)
    offset = ws - T.shape[1] - PAD  # strip position p <-> disparity d = offset - p
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
