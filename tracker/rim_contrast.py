"""How well each side of a solid body's outline is placed: the contrast of its rim (issue 12 item 1).

A solid body's outline is drawn where eq. (9) and the temporal model find it differs from the
background. Where its rim stands out strongly (a lit ball against a dark hedge), the threshold places each
side on the right pixel: on approach:body, a sphere at 30 to 12 m, eq. (10)'s centroid lay within 0.02 px
rms of the true silhouette's in the 153 frames where under a tenth of its rim was faint. Where the rim
fades into the background (shaded, curving away, a texture like the background's), pixels along it fall
either side of the threshold with the noise and the light, and the side lies a fraction of a pixel off:
0.24 px median |error| along x where that share was 0.1 to 0.3 on the same sphere, and on the walkers
errors grow with the share (walk:body: 0.11 px median |x error| at a faint share of 0.2-0.3, 0.19 at
0.3-0.4, 0.30 at 0.4-0.5, 0.9 above).

A rim pixel counts as faint where |Γ - g B| (the temporal model's residual, Γ the left image, B the
background at gain g) is under `faint_level` (2 ε: twice the threshold of eq. 9). Each side's 1-σ is
`side_px` times its rim's faint share f: the centroid's error grows about linearly with the faint share,
and a side whose whole rim is faint may lose a band of a pixel or two (tracker.rim recovers part of
it). The two sides along an axis move independently, each moving the centroid by half its shift, so the
centroid's 1-σ along x is √(σ_left² + σ_right²) / 2 (and along y with top and bottom). side_px = 1.7 px
from the frames seen whole (98 % or more) of the six still `NAME:body` scenarios: the rms |x error| of the
centroid against the true silhouette's was 0.02-0.21 px where the left and right sides' shares summed
to under 0.2, 0.18-0.26 px at 0.2-0.4, 0.29-0.36 at 0.4-0.6, 0.35-0.53 at 0.6-0.8 (about 0.6 px times
the sum: 1.7 / (2 √2) with the sum split evenly), and 0.57-1.18 above (the walkers' heavy tail, whose x
has a prior of its own: tracker.localize.SolidPrior.upright_x_var). The fixed term it replaces, 0.5 /
√2 = 0.35 px, is this at a summed share of 0.6.

On approach:body the sphere's azimuth and elevation NEES went 0.68 -> 0.91 and 0.17 -> 0.80 (within 1σ
0.74 -> 0.70 and 0.95 -> 0.78); the other still scenes' figures moved by under 0.01 but for elevation
NEES (walk 1.39 -> 1.35, illumination 1.45 -> 1.39, endless 2.00 -> 1.77). With the cameras moving
there is no temporal model and the fixed term stays.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.visibility import sides

BoolA = NDArray[np.bool_]
_RIM = np.ones((3, 3), np.uint8)  # a pixel with a neighbour outside the mask is on its rim


@dataclass(frozen=True)
class RimContrastConfig:
    """faint_level: a rim pixel is faint where its residual |Γ - g B| is under this (grey levels); side_px: a
    side's 1-σ (px) where all of its rim is faint (see the module's docstring)."""

    faint_level: float = 24.0
    side_px: float = 1.7


def faint_shares(mask: BoolA, box: tuple[int, int, int, int], image: NDArray[np.uint8],
                 background: NDArray[np.float32], gain: float, cfg: RimContrastConfig
                 ) -> tuple[float, float, float, float]:
    """The share of each side's rim (left, right, top, bottom) that is faint: the mask's own 1-px rim (its
    pixels with a 3x3 neighbour outside it), split into sides about its centroid (tracker.visibility.sides).
    mask: (h, w) over box (x0, y0, x1, y1) of the left image `image` (H, W); background: the temporal model
    B (H, W) at gain 1. A side with no rim pixels has share 0."""
    x0, y0, x1, y1 = box
    m8 = mask.view(np.uint8)
    rim = mask & (cv2.erode(m8, _RIM, borderType=cv2.BORDER_CONSTANT, borderValue=0) == 0)
    mom = cv2.moments(m8, binaryImage=True)
    if mom["m00"] == 0:
        return 0.0, 0.0, 0.0, 0.0
    _, _, bw, bh = cv2.boundingRect(m8)
    centre, half = (mom["m10"] / mom["m00"], mom["m01"] / mom["m00"]), (max(bw / 2.0, 1.0), max(bh / 2.0, 1.0))
    residual = np.abs(image[y0:y1, x0:x1].astype(np.float32) - np.float32(gain) * background[y0:y1, x0:x1])
    faint = residual < cfg.faint_level
    return tuple(float(np.count_nonzero(faint[ys, xs])) / xs.size if xs.size else 0.0  # type: ignore[return-value]
                 for ys, xs in sides(rim, centre, half))


def rim_sigma_px(shares: tuple[float, float, float, float], cfg: RimContrastConfig) -> tuple[float, float]:
    """The centroid's 1-σ (px, x and y) from its outline's four sides, each side_px times its faint share
    f: √(σ_left² + σ_right²) / 2 along x, the same with top and bottom along y."""
    v = [(cfg.side_px * f) ** 2 for f in shares]
    return float(np.sqrt(v[0] + v[1]) / 2.0), float(np.sqrt(v[2] + v[3]) / 2.0)
