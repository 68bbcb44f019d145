"""Sub-pixel stereo matching along the epipolar line of a rectified pair.

Conventions: images are rectified grey uint8 of shape (H, W); a left point (x, y) in pixels (sub-pixel
floats allowed, pixel centres at integers) matches the right point (x - d, y), d = disparity >= 0 (px).

Two steps: an integer search of normalised cross-correlation (cv2.matchTemplate, TM_CCOEFF_NORMED) over
d in [0, max_disparity], then an iterative 1-D Lucas-Kanade (Gauss-Newton) refinement of d that minimises
sum w (L(u) - a R(u - d) - b)^2 with Catmull-Rom (cubic) interpolation of the right image along the row
and a gain a / offset b model. A sub-pixel row y is sampled bilinearly in both images alike. The normal
equations are formed from a small Gram matrix of the strip windows around the integer peak, so each
iteration costs a few scalar operations. Unlike a parabola fit on the correlation curve, the refinement
is not pixel-locked (tests/test_stereo.py checks this on exact synthetic shifts).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.frames import U8, check_pair

F64 = NDArray[np.float64]
F32 = NDArray[np.float32]

PAD = 2  # extra strip columns on each side for interpolation and the gradient
_MAX_ITER = 10
_STEP_TOL = 5e-3  # px: the Gauss-Newton update that ends the iteration (it is still applied)
# a region's robust fit (refine_strip, `outliers`): residuals over OUTLIER_K robust standard deviations
# are left out, where they weigh at least OUTLIER_MIN of the region (a Gaussian's tail beyond 3 σ is
# 0.27 %: a region the model fits keeps its one fit), at most ROBUST_ROUNDS times
OUTLIER_K = 3.0
OUTLIER_MIN = 0.01
ROBUST_ROUNDS = 4
NOISE_FLOOR = 1.0  # grey levels: the least robust standard deviation (exact synthetic shifts leave ~0)


@dataclass(frozen=True)
class RegionMatch:
    """One disparity for a region. disparity and sigma in px (right x = x - disparity); score is the
    weighted zero-mean normalised correlation in [-1, 1] at the final disparity; gain = a of the
    model L ~ a R + b (left/right contrast ratio)."""

    disparity: float
    sigma: float
    score: float
    gain: float


@dataclass(frozen=True)
class StripFit:
    d: float
    sigma: float
    score: float
    gain: float


def check_images(left: object, right: object, max_disparity: object) -> tuple[U8, U8]:
    """Validate a rectified pair and the disparity bound; FrameError / ValueError with a one-line reason."""
    check_pair(left, right)
    if isinstance(max_disparity, bool) or not isinstance(max_disparity, (int, np.integer)):
        raise ValueError(f"max_disparity must be an integer, got {max_disparity!r}")
    if max_disparity < 0:
        raise ValueError(f"max_disparity must be >= 0, got {max_disparity}")
    assert isinstance(left, np.ndarray) and isinstance(right, np.ndarray)
    return left, right


def _band_gram(T: NDArray[np.floating], S: NDArray[np.floating], w: F64 | None, k: int) -> list[list[float]]:
    """Weighted Gram matrix (7, 7) of the mean-removed strip windows k-2 .. k+3 and the template.

    T: template (h, n); S: strip (h, m); w: weights (h*n,) or None. Window j is strip columns
    j .. j+n-1 flattened like the template; row/column 6 of the result is the template.
    """
    h, n = T.shape
    A = np.empty((7, h * n))
    cols = np.ascontiguousarray(S[:, k - 2 : k + 3 + n], dtype=np.float64)
    A[:6].reshape(6, h, n)[...] = np.ndarray((6, h, n), np.float64, cols, 0, (8, cols.strides[0], 8))
    A[6] = T.ravel()
    if w is None:
        A -= (A.sum(axis=1) / A.shape[1])[:, None]
        G = A @ A.T
    else:
        A -= ((A @ w) / w.sum())[:, None]
        G = (A * w) @ A.T
    rows: list[list[float]] = G.tolist()
    return rows


def catmull_rom(f: float) -> tuple[list[float], list[float]]:
    """Catmull-Rom interpolation weights for taps -1, 0, 1, 2 at fraction f in [0, 1), and their
    derivatives with respect to f."""
    f2, f3 = f * f, f * f * f
    u = [0.5 * (-f3 + 2 * f2 - f), 0.5 * (3 * f3 - 5 * f2 + 2), 0.5 * (-3 * f3 + 4 * f2 + f), 0.5 * (f3 - f2)]
    v = [
        0.5 * (-3 * f2 + 4 * f - 1),
        0.5 * (9 * f2 - 10 * f),
        0.5 * (-9 * f2 + 8 * f + 1),
        0.5 * (3 * f2 - 2 * f),
    ]
    return u, v


def _forms(G: list[list[float]], j: int, u: list[float], v: list[float]) -> tuple[float, ...]:
    """With M = G[j:j+4, j:j+4] and m = G[j:j+4, 6]: (u'Mu, v'Mu, v'Mv, u'm, v'm), unrolled for speed."""
    g0, g1, g2, g3 = G[j], G[j + 1], G[j + 2], G[j + 3]
    u0, u1, u2, u3 = u
    v0, v1, v2, v3 = v
    mu0 = g0[j] * u0 + g0[j + 1] * u1 + g0[j + 2] * u2 + g0[j + 3] * u3
    mu1 = g1[j] * u0 + g1[j + 1] * u1 + g1[j + 2] * u2 + g1[j + 3] * u3
    mu2 = g2[j] * u0 + g2[j + 1] * u1 + g2[j + 2] * u2 + g2[j + 3] * u3
    mu3 = g3[j] * u0 + g3[j + 1] * u1 + g3[j + 2] * u2 + g3[j + 3] * u3
    mv0 = g0[j] * v0 + g0[j + 1] * v1 + g0[j + 2] * v2 + g0[j + 3] * v3
    mv1 = g1[j] * v0 + g1[j + 1] * v1 + g1[j + 2] * v2 + g1[j + 3] * v3
    mv2 = g2[j] * v0 + g2[j + 1] * v1 + g2[j + 2] * v2 + g2[j + 3] * v3
    mv3 = g3[j] * v0 + g3[j + 1] * v1 + g3[j + 2] * v2 + g3[j + 3] * v3
    return (
        u0 * mu0 + u1 * mu1 + u2 * mu2 + u3 * mu3,
        v0 * mu0 + v1 * mu1 + v2 * mu2 + v3 * mu3,
        v0 * mv0 + v1 * mv1 + v2 * mv2 + v3 * mv3,
        u0 * g0[6] + u1 * g1[6] + u2 * g2[6] + u3 * g3[6],
        v0 * g0[6] + v1 * g1[6] + v2 * g2[6] + v3 * g3[6],
    )


def refine_strip(T: NDArray[np.floating], S: NDArray[np.floating], w: F64 | None, p: float, k: int,
                 robust: bool = False) -> StripFit | None:
    """Gauss-Newton (1-D Lucas-Kanade) refinement of the strip position p of template T in strip S.

    T: (h, n); S: (h, m) with S[:, j] at right-image position XS + j; w: weights (h*n,) or None. The
    template at strip position p samples the strip at p, p+1, .., p+n-1 (Catmull-Rom interpolation along
    the row); the model is T ~ alpha R(p) + beta. Needs 2 <= k and k + 3 + n <= m; p must stay in
    [k - 1, k + 2). Returns StripFit with d = -p (caller adds X0 - XS) or None if p leaves that range or the
    fit is degenerate (no horizontal texture, non-positive gain). robust: pixels the model does not fit
    (`outliers`) are left out and the fit is done again from where it ended, up to ROBUST_ROUNDS times;
    the score stays the first fit's, over all the weighted pixels.
    """
    first = fit = refine_gram(_band_gram(T, S, w, k), float(T.size) if w is None else float(w.sum()), p, k)
    wv = np.ones(T.size) if w is None else w
    for _ in range(ROBUST_ROUNDS if robust else 0):
        if fit is None:
            return None
        out = outliers(T, S, wv, fit, k)
        if out is None:
            break
        wv = np.where(out, 0.0, wv)
        fit = refine_gram(_band_gram(T, S, wv, k), float(wv.sum()), -fit.d, k)
    # the score stays the whole region's: how well it matches is what verification asks (MIN_SCORE)
    return fit if fit is None or first is None else StripFit(fit.d, fit.sigma, first.score, fit.gain)


def outliers(T: NDArray[np.floating], S: NDArray[np.floating], w: F64, fit: StripFit, k: int
             ) -> NDArray[np.bool_] | None:
    """The pixels (h*n,) of a region's fit (refine_strip's, at strip position -fit.d) whose residual
    r = T - alpha R - beta lies over OUTLIER_K robust standard deviations (1.4826 times the weighted pixels'
    median |r|, at least NOISE_FLOOR grey levels) from it; None where they weigh under OUTLIER_MIN of the
    region or leave under half of it (then nothing is left out).

    Pixels where the two cameras see different things, not the same surface displaced, break the model
    the least-squares fit assumes and pull its disparity by far more than its 1-σ: a walker's arms before
    its torso, the gap between them dark to one camera and closed to the other (endless:body frame 1210,
    a person standing at 10 m: 15 to 47 grey levels of residual on the columns at the gaps, against about
    2 elsewhere; the whole outline's fit 0.35 px off the seen surface's disparity, 14 times its 1-σ)."""
    p = -fit.d
    i = min(max(math.floor(p), k - 1), k + 1)  # the last Gauss-Newton step may end just past the cells
    u, _ = catmull_rom(p - i)
    n = T.shape[1]
    R = np.zeros(T.shape)
    for t in range(4):  # the right image at the fit, Catmull-Rom along the row
        R += u[t] * np.asarray(S[:, i - 1 + t : i - 1 + t + n], np.float64)
    return residual_outliers(np.asarray(T, np.float64).ravel(), R.ravel(), w, fit.gain)


def residual_outliers(t: F64, r: F64, w: F64, gain: float | None = None) -> NDArray[np.bool_] | None:
    """`outliers` from the template's pixels t (N,), the right image r (N,) interpolated where they match
    and their weights w (N,): r's gain alpha (the fit's, or with gain None its weighted least-squares
    gain), beta = t̄ - alpha r̄ (weighted means), the residuals t - alpha r - beta."""
    on = w > 0
    wsum = float(w.sum())
    if wsum <= 0.0:
        return None
    tm, rm = float(w @ t) / wsum, float(w @ r) / wsum
    if gain is None:
        var = float(w @ ((r - rm) ** 2))
        if var <= 0.0:
            return None
        gain = float(w @ ((t - tm) * (r - rm))) / var
    res = np.abs(t - tm - gain * (r - rm))
    s = max(1.4826 * float(np.median(res[on])), NOISE_FLOOR)
    out = on & (res > OUTLIER_K * s)
    dropped = float(w[out].sum())
    if dropped < OUTLIER_MIN * wsum or dropped > 0.5 * wsum:
        return None
    return out


def refine_gram(G: list[list[float]], wsum: float, p: float, k: int) -> StripFit | None:
    """refine_strip from the weighted Gram matrix (7, 7) of its band windows k-2 .. k+3 and the template
    (_band_gram; wsum: the sum of the weights): the Gauss-Newton iteration alone."""
    tt = G[6][6]
    for it in range(_MAX_ITER + 1):
        i = math.floor(p)
        if not k - 1 <= i <= k + 1:
            return None
        u, v = catmull_rom(p - i)
        j = i - k + 1  # first band window used by cell i
        a, b, c, pt, qt = _forms(G, j, u, v)
        det = a * c - b * b
        if a <= 0.0 or det <= 1e-12 * a * c:
            return None
        alpha = (c * pt - b * qt) / det  # T ~ alpha R + gamma dR/dp + beta, gamma = alpha * dp
        gamma = (a * qt - b * pt) / det
        if alpha <= 0.0:
            return None
        dp = gamma / alpha
        if abs(dp) < _STEP_TOL or it == _MAX_ITER:
            resid = max(tt - alpha * pt - gamma * qt, 0.0)  # sum w r^2 at the least-squares solution
            sigma = math.sqrt(resid / max(wsum - 3.0, 1.0) * a / det) / alpha
            score = pt / math.sqrt(a * tt) if tt > 0.0 else 0.0
            return StripFit(-(p + dp), sigma, score, alpha)
        p += max(-1.0, min(1.0, dp))
    return None  # pragma: no cover - the loop always returns


def _subpixel_peak(r: F64, k: int) -> float:
    """Parabola vertex offset (in index units, within +-0.5) around the interior peak r[k]."""
    y0, y1, y2 = float(r[k - 1]), float(r[k]), float(r[k + 1])
    den = y0 - 2.0 * y1 + y2
    return 0.0 if den >= 0.0 else max(-0.5, min(0.5, 0.5 * (y0 - y2) / den))


def _second_peak(r: list[float], k: int) -> float:
    """Highest value of the 1-D correlation r outside the main lobe (monotone descent) around index k."""
    lo = k
    while lo > 0 and r[lo - 1] <= r[lo]:
        lo -= 1
    hi = k
    while hi < len(r) - 1 and r[hi + 1] <= r[hi]:
        hi += 1
    rest = r[:lo] + r[hi + 1 :]
    return max(rest) if rest else -1.0


def zncc_weighted(S: NDArray[np.floating], T: NDArray[np.floating], w: NDArray[np.floating]) -> F64:
    """Weighted zero-mean normalised cross-correlation of template T (h, n) with weights w (h, n) at every
    column position of strip S (h, m): shape (m - n + 1,), -1 where a window is flat. Direct sums (OpenCV's
    masked TM_CCOEFF_NORMED goes through several full correlations and is slower for small searches)."""
    ws = (w / max(float(w.sum()), 1e-12)).astype(np.float32)
    Tc = T.astype(np.float32) - np.float32((T * ws).sum())
    var_t = float((ws * Tc * Tc).sum())
    S32 = S.astype(np.float32)
    # three plain correlations (OpenCV, fast): Σ w W, Σ w W², Σ w W (T - T̄) at every position
    mean_w = cv2.matchTemplate(S32, ws, cv2.TM_CCORR)[0].astype(np.float64)
    mean_w2 = cv2.matchTemplate(S32 * S32, ws, cv2.TM_CCORR)[0].astype(np.float64)
    num = cv2.matchTemplate(S32, ws * Tc, cv2.TM_CCORR)[0].astype(np.float64)
    var_w = mean_w2 - mean_w * mean_w
    den = np.sqrt(np.maximum(var_w, 0.0) * var_t)
    return np.asarray(np.where(den > 1e-6, num / np.maximum(den, 1e-12), -1.0), dtype=np.float64)


def match_strip(
    T: F32, S: F32, w: F32 | None, offset: int, span: int, min_score: float, uniqueness: float,
    robust: bool = False,
) -> StripFit | None:
    """Integer ZNCC search (cv2.matchTemplate) then Gauss-Newton refinement of a template in a strip.

    T: template (h, n); S: strip (h, span + n + 2 * PAD); w: weights (h, n) or None. Template column c
    lies at left position X0 + c, strip column j at right position XS + j, offset = X0 - XS, and the
    candidate disparities d = offset - p for strip positions p = PAD .. PAD + span. Returns None if the
    peak is on the border of the candidates, below min_score, within `uniqueness` of a second peak, or the
    refinement fails or moves by more than 1 px.
    """
    if w is None:
        r = cv2.matchTemplate(S[:, PAD:-PAD], T, cv2.TM_CCOEFF_NORMED)[0].astype(np.float64)
    else:
        r = zncc_weighted(S[:, PAD:-PAD], T, w)
    kk = int(np.argmax(r))
    if kk == 0 or kk == span or float(r[kk]) < min_score:
        return None
    if float(r[kk]) - _second_peak(r.tolist(), kk) < uniqueness:
        return None
    p0 = kk + PAD + _subpixel_peak(r, kk)
    fit = refine_strip(T, S, None if w is None else w.ravel().astype(np.float64), p0, kk + PAD, robust)
    if fit is None or abs(fit.d + p0) > 1.0:
        return None
    return StripFit(offset + fit.d, fit.sigma, fit.score, fit.gain)


def match_region(
    left: U8,
    right: U8,
    mask: NDArray[np.generic],
    x0: int,
    y0: int,
    max_disparity: int,
    d0: float | None = None,
    *,
    search_radius: int = 3,
    min_score: float = 0.5,
    uniqueness: float = 0.02,
    robust: bool = True,
) -> RegionMatch | None:
    """One disparity for the masked left region, mask-weighted.

    mask: (h, w) array covering the left pixels [y0, y0 + h) x [x0, x0 + w) (integer top-left corner);
    bool or integer masks count non-zero pixels, float masks are weights clipped to [0, 1]. d0: a prior
    disparity (px); the integer search then covers d0 +- search_radius instead of [0, max_disparity].
    Returns None when the region or its search strip leaves the image, the region has fewer than 8
    (weighted) pixels, the correlation peak is on the search border, below min_score or not unique by
    `uniqueness`, or the refinement fails. sigma comes from the Gauss-Newton normal matrix scaled by the
    residual variance, so it assumes independent pixel noise. robust: the pixels the model does not fit
    are left out of the refinement (refine_strip, `outliers`).
    """
    left, right = check_images(left, right, max_disparity)
    m = np.asarray(mask)
    if m.ndim != 2 or m.size == 0:
        raise ValueError(f"mask must be a non-empty 2-D array, got shape {m.shape}")
    if np.issubdtype(m.dtype, np.floating):
        wgt = np.clip(np.nan_to_num(m.astype(np.float64)), 0.0, 1.0)
    else:
        wgt = (m != 0).astype(np.float64)
    H, W = left.shape
    mh, mw = m.shape
    x0, y0 = int(x0), int(y0)
    if x0 < 0 or y0 < 0 or x0 + mw + PAD > W or y0 + mh > H or float(wgt.sum()) < 8.0:
        return None
    lo, hi = 0, max_disparity
    if d0 is not None:
        if not math.isfinite(d0):
            raise ValueError(f"d0 must be finite, got {d0}")
        lo, hi = max(0, math.floor(d0) - search_radius), min(max_disparity, math.ceil(d0) + search_radius)
    hi = min(hi, x0 - PAD)
    if hi - lo < 2:
        return None
    T = left[y0 : y0 + mh, x0 : x0 + mw].astype(np.float32)
    xs0 = x0 - hi - PAD
    S = right[y0 : y0 + mh, xs0 : x0 + mw - lo + PAD].astype(np.float32)
    fit = match_strip(T, S, wgt.astype(np.float32), hi + PAD, hi - lo, min_score, uniqueness, robust)
    if fit is None:
        return None
    return RegionMatch(disparity=fit.d, sigma=fit.sigma, score=fit.score, gain=fit.gain)


def refine_region(
    left: U8, right: U8, mask: NDArray[np.generic], x0: int, y0: int, d0: float, *, min_score: float = 0.5,
    robust: bool = True,
) -> RegionMatch | None:
    """Like match_region with a good prior d0 (within about a pixel, e.g. a track's prediction): the
    Gauss-Newton refinement starts at d0 with no integer search. None when it leaves d0 ± 1 px, the fit
    degenerates or scores below min_score (then search with match_region). robust: as match_region's."""
    left, right = check_images(left, right, 0)
    if not math.isfinite(d0) or d0 < 0:
        raise ValueError(f"d0 must be finite and >= 0, got {d0}")
    m = np.asarray(mask)
    wgt = (m != 0) if not np.issubdtype(m.dtype, np.floating) else np.clip(np.nan_to_num(m), 0.0, 1.0)
    mh, mw = m.shape
    lo, hi = max(0, math.floor(d0) - 3), math.ceil(d0) + 3
    if x0 - hi - PAD < 0 or x0 + mw + PAD > left.shape[1] or y0 < 0 or y0 + mh > left.shape[0]:
        return None
    if float(wgt.sum()) < 8.0:
        return None
    T = left[y0 : y0 + mh, x0 : x0 + mw].astype(np.float32)
    xs0 = x0 - hi - PAD
    S = right[y0 : y0 + mh, xs0 : x0 + mw - lo + PAD].astype(np.float32)
    offset = hi + PAD  # strip position p <-> disparity d = offset - p
    p0 = offset - d0
    fit = refine_strip(T, S, wgt.astype(np.float64).ravel(), p0, math.floor(p0), robust)
    if fit is None or abs(fit.d + p0) > 1.0 or fit.score < min_score:
        return None
    return RegionMatch(disparity=offset + fit.d, sigma=fit.sigma, score=fit.score, gain=fit.gain)
