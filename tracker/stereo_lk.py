"""Two-dimensional Lucas-Kanade refinement of a point's disparity, for real rectified pairs.

A real rectification leaves rows misaligned by a tenth of a pixel or more (Middlebury pairs: 0.03 to
0.12 px median; a calibrated rig: its rectified row error). Along oblique texture a row offset δy moves a
purely horizontal match by -(Σ g_x g_y / Σ g_x²) δy, so the 1-D estimate is biased there. This refinement
fits the disparity d together with a row offset δy, a gain a and an offset b:

    min Σ w (L(x, y) - a R(x - d, y + δy) - b)²        (Gauss-Newton, Catmull-Rom sampling of R)

over the window, with adaptive support weights w = exp(-|L - L_c| / γ) (pixels unlike the centre, often
another surface behind a depth edge, count less). σ_d is the marginal 1-σ of d from the normal matrix
scaled by the weighted residual variance, so a window whose texture cannot tell d from δy has a large σ_d.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

F64 = NDArray[np.float64]
F32 = NDArray[np.float32]

_MAX_ITER = 8
_STEP_TOL = 5e-3  # px: the Gauss-Newton update that ends the iteration


@dataclass(frozen=True)
class Fit2D:
    """d: disparity (px, right x = x - d); dy: row offset (px, right y = y + dy); sigma: 1-σ of d (px);
    gain: a of L ~ a R + b."""

    d: float
    dy: float
    sigma: float
    gain: float


def support_weights(T: F32, gamma: float) -> F32:
    """Adaptive support weights (h, n) of a template: exp(-|T - T_c| / γ), T_c the mean of its central
    3x3 pixels, γ in grey levels."""
    h, n = T.shape
    c = float(T[h // 2 - 1 : h // 2 + 2, n // 2 - 1 : n // 2 + 2].mean())
    w: F32 = np.exp(-np.abs(T - np.float32(c)) / np.float32(gamma)).astype(np.float32)
    return w


def _taps(f: float) -> F64:
    """Catmull-Rom weights of taps -1, 0, 1, 2 at fraction f in [0, 1)."""
    f2, f3 = f * f, f * f * f
    return np.array([0.5 * (-f3 + 2 * f2 - f), 0.5 * (3 * f3 - 5 * f2 + 2), 0.5 * (-3 * f3 + 4 * f2 + f),
                     0.5 * (f3 - f2)])


def _sample(right: NDArray[np.uint8], cx: float, cy: float, shape: tuple[int, int]) -> tuple[F64, F64, F64] | None:
    """The right image's (h, n) patch centred on (cx, cy) and its x, y central differences, from one
    (h + 2, n + 2) patch interpolated by separable Catmull-Rom cubics (a pure translation, so exact
    positions; OpenCV's remap would quantise them to 1/32 px). None if the patch leaves the image."""
    h, n = shape[0] + 2, shape[1] + 2
    x0, y0 = cx - 0.5 * (n - 1), cy - 0.5 * (h - 1)
    ix, iy = math.floor(x0), math.floor(y0)
    H, W = right.shape
    if ix < 1 or iy < 1 or ix + n + 2 > W or iy + h + 2 > H:
        return None
    block = right[iy - 1 : iy + h + 2, ix - 1 : ix + n + 2].astype(np.float64)
    u, v = _taps(x0 - ix), _taps(y0 - iy)
    rows = u[0] * block[:, 0:n] + u[1] * block[:, 1 : n + 1] + u[2] * block[:, 2 : n + 2] + u[3] * block[:, 3 : n + 3]
    P = v[0] * rows[0:h] + v[1] * rows[1 : h + 1] + v[2] * rows[2 : h + 2] + v[3] * rows[3 : h + 3]
    return P[1:-1, 1:-1], 0.5 * (P[1:-1, 2:] - P[1:-1, :-2]), 0.5 * (P[2:, 1:-1] - P[:-2, 1:-1])


def refine_2d(T: F32, right: NDArray[np.uint8], xc: int, y: float, d0: float, w: F32) -> Fit2D | None:
    """Refine the disparity d0 of template T (h, n), the left window centred on (xc, y), in the right
    image (H, W) uint8 with weights w (h, n). None when the fit degenerates (no texture, gain <= 0)."""
    t, ww = T.astype(np.float64).ravel(), w.astype(np.float64).ravel()
    d, dy = d0, 0.0
    for _ in range(_MAX_ITER):
        sample = _sample(right, xc - d, y + dy, T.shape)
        if sample is None:
            return None
        P, gx, gy = sample
        p = P.ravel()
        # gain and offset for the current warp, then one Gauss-Newton step in (d, δy, a, b)
        sw = ww.sum()
        pm, tm = (ww @ p) / sw, (ww @ t) / sw
        vp = ww @ ((p - pm) ** 2)
        if vp <= 1e-9:
            return None
        a = (ww @ ((p - pm) * (t - tm))) / vp
        b = tm - a * pm
        if a <= 0.0:
            return None
        J = np.stack([-a * gx.ravel(), a * gy.ravel(), p, np.ones_like(p)], axis=1)
        r = t - (a * p + b)
        JW = J * ww[:, None]
        N = JW.T @ J
        try:
            step = np.linalg.solve(N, JW.T @ r)
        except np.linalg.LinAlgError:
            return None
        d, dy = d + float(step[0]), dy + float(step[1])
        if abs(step[0]) < _STEP_TOL and abs(step[1]) < _STEP_TOL:
            break
    try:
        cov = np.linalg.inv(N)
    except np.linalg.LinAlgError:
        return None
    s2 = float(ww @ (r * r)) / max(float(ww.sum()) - 4.0, 1.0)
    return Fit2D(d, dy, math.sqrt(max(float(cov[0, 0]) * s2, 0.0)), float(a))
