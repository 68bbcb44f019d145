"""How far off a target's disparity may lie beyond what the matcher's own 1-σ says (issue 12 item 1).

The region match (tracker.stereo.refine_strip) gives the disparity's 1-σ from its Gauss-Newton normal
matrix scaled by the residual variance: right for independent pixel noise. A target's residuals are not
independent: the two cameras sample its texture at different sub-pixel phases (a texture smooth over a
few pixels leaves residuals correlated over as many), and the interpolation of the right image errs by an
amount that depends on the texture and on the disparity's fraction. And the disparity may vary over the
region (a person board turned from the rig's axis: at 3 m and 20° off it, 3 px across its width), so that
the one disparity fitted, weighted by the texture's gradients, belongs to a point other than the centroid.
On the scenes of `tmeye eval` these made the disparity's error 1.3 (walk) to 20 (endless) times the
matcher's 1-σ (0.026 and 0.137 px rms against 0.008 and 0.006 px).

All of these show in how the disparities of parts of the region disagree: the region is cut into a grid of
`COLUMNS` x `ROWS` parts about the centre of the window the matcher uses, each part matched on its own, and
the standard error of their mean, s / √n (s their sample standard deviation, n the parts matched), is the
1-σ of the whole region's disparity: the whole's fit is about their mean. The grid has 8 parts so that the
σ estimate itself is not too noisy (with 4 parts the normalised errors follow Student's t with 3 degrees
of freedom, whose variance is 3).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

BoolA = NDArray[np.bool_]
U8 = NDArray[np.uint8]
F64 = NDArray[np.float64]
COLUMNS, ROWS = 4, 2
MIN_PARTS = 5


def scatter_sigma(disparities: list[float]) -> float:
    """The standard error of the mean of the parts' disparities (px), s / √n; 0 with fewer than MIN_PARTS
    (too few to tell: the matcher's own σ then stands)."""
    n = len(disparities)
    if n < MIN_PARTS:
        return 0.0
    return float(np.std(disparities, ddof=1) / np.sqrt(n))


def part_disparities(left: U8, right: U8, core: NDArray[np.generic], off: int, d: float,
                     min_score: float, iterations: int = 6) -> list[float]:
    """The disparities (px) of the COLUMNS x ROWS parts of a matched region, all parts in each pass.

    left, right: rectified strips (h, m) over the region's rows; core: the region's weights (h, n), nonzero
    where it is matched, its column j at strip column off + j; d: the whole region's disparity. Each part
    (the window cut into a grid) is refined from d by tracker.stereo.refine_strip's Gauss-Newton model with
    its own gain and offset, T ~ alpha R(x) + beta + gamma dR/dx at x = off + j - d_part (Catmull-Rom along
    the row), d_part moving by -gamma / alpha (at most 1 px a step) until the steps are below 0.005 px.
    A part is left out with fewer than 8 pixels, a degenerate fit (no horizontal texture, non-positive
    gain), an answer over 1 px from d, or a score (weighted correlation of T with R) below min_score."""
    h, n = core.shape
    P = COLUMNS * ROWS
    if h == 0 or n == 0 or off - d - 2.0 < 0 or off + n - d + 3.0 > right.shape[1]:
        return []
    w = np.asarray(core) != 0
    rows, cols = np.nonzero(w)
    lab = (rows * ROWS // h) * COLUMNS + cols * COLUMNS // n
    cnt = np.bincount(lab, minlength=P).astype(np.float64)
    T = left[rows, off + cols].astype(np.float64)
    flat = right.astype(np.float64).ravel()
    base = rows * right.shape[1] + off + cols  # flat index of column off + j on each pixel's row
    dp = np.full(P, float(d))
    for _ in range(max(iterations, 1)):
        a, b, c, pt, qt, tt = _moments(flat, base, -dp[lab], lab, T, P)  # x - (off + j) = -d_part
        with np.errstate(divide="ignore", invalid="ignore"):
            det = a * c - b * b
            alpha = (c * pt - b * qt) / det
            step = np.nan_to_num((a * qt - b * pt) / det / alpha)  # gamma / alpha: x moves by it
            score = pt / np.sqrt(a * tt)
        dp = np.clip(dp - np.clip(step, -1.0, 1.0), d - 1.5, d + 1.5)  # on the strip; judged against d +- 1
        if np.all(np.abs(step) < 0.005):  # converged: the fit's figures are those at the final step's start
            break
    ok = (cnt >= 8) & (a > 0) & (det > 1e-12 * a * c) & (alpha > 0) & (np.abs(dp - d) <= 1.0) & (score >= min_score)
    return [float(dp[k]) for k in np.flatnonzero(ok)]


def _moments(flat: F64, base: NDArray[np.intp], shift: F64, lab: NDArray[np.intp], T: F64, P: int
             ) -> tuple[F64, F64, F64, F64, F64, F64]:
    """Per part, mean-removed sums of R R, R D, D D, R T, D T, T T, where R and D are the right strip and its
    derivative along the row (Catmull-Rom) at each pixel's column shifted by `shift` (px)."""
    i = np.floor(shift)
    f = shift - i
    at = base + i.astype(np.intp)
    f2, f3 = f * f, f * f * f
    taps = [flat[at + k] for k in (-1, 0, 1, 2)]
    R = 0.5 * ((-f3 + 2 * f2 - f) * taps[0] + (3 * f3 - 5 * f2 + 2) * taps[1] + (-3 * f3 + 4 * f2 + f) * taps[2]
               + (f3 - f2) * taps[3])
    D = 0.5 * ((-3 * f2 + 4 * f - 1) * taps[0] + (9 * f2 - 10 * f) * taps[1] + (-9 * f2 + 8 * f + 1) * taps[2]
               + (3 * f2 - 2 * f) * taps[3])
    cnt = np.maximum(np.bincount(lab, minlength=P), 1).astype(np.float64)
    s = [np.bincount(lab, weights=q, minlength=P) for q in (R, D, T, R * R, R * D, D * D, R * T, D * T, T * T)]
    mR, mD, mT = s[0] / cnt, s[1] / cnt, s[2] / cnt  # the offset beta: moments about the part's means
    return (s[3] - s[0] * mR, s[4] - s[0] * mD, s[5] - s[1] * mD, s[6] - s[0] * mT, s[7] - s[1] * mT,
            s[8] - s[2] * mT)
