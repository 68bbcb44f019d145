"""Which part of a round body's seen face its disparity measures (issue 12 item 1).

A body that is neither upright nor wide (SolidPrior: a ball, a head) is matched on its outline's central
window only, `MATCH_HALF` (tracker.strips.first_window), and within it on the outline's core, shrunk by
about a pixel so that no background enters the match (tracker.strips.Strips.core). SolidPrior's ρ puts the
centre ρ/2 · e behind the mean of the whole seen face (2R/3 for a sphere of radius R: the mean of
√(R² - r²) over the disc it is seen as). The pixels matched are not the whole face: a near ball wider than
the window is matched on its middle, which stands out towards the cameras, and even a small one loses its
rim, which lies deepest. Both put the face measured nearer than the face's mean, so the centre was placed
too near: on approach:body (a ball 0.6 m across) by 3.5 % of the range at 2-4 m (its disparity 2.6 % over
the seen face's), 1.4 % at 4-6 m and 0.3 % beyond 8 m.

`matched_factor` is how much higher, on a surface round like a sphere's over the outline (an ellipse on its
box, each pixel's height √(1 - q²) at normalised radius q), the pixels matched stand than the whole
outline's: the mean height over the core within the window over the mean over the outline. The centre's
depth behind the face measured is that factor times SolidPrior's (SolidPrior.behind_face_px, `matched`).
Predicted for a disc 14, 35, 72 and 120 px across: the disparity 0.17, 0.21, 1.28 and 2.92 % over the face's;
measured on approach:body at those widths 0.28, 0.16-0.21, 1.12 and 2.59 %. With it (and SolidPrior's ρ
refitted about it) the ball's range bias was -0.84 % at 2-4 m and -0.03 to -0.16 % beyond 6 m
(2026-12-06, docs/evaluation.md). A piece of a body seen upright whole before (a person's part beside
what hides the rest) keeps the factor 1: it is no sphere (tracker.pipeline).
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.strips import MATCH_HALF

BoolA = NDArray[np.bool_]
_CORE = np.ones((3, 3), np.uint8)  # Strips.core's erosion


def matched_factor(mask: BoolA, half: tuple[int, int] = MATCH_HALF) -> float:
    """The mean height of a sphere-like surface over the outline `mask` ((h, w) bool over its box, raw left
    pixels) at the pixels its disparity is matched on (its core, eroded by a 3 x 3 pixel, within the central
    window of half size `half`, px, about the outline's box centre) over that mean over the whole outline;
    1 where nothing of the core lies in the window. At least 1 for an outline that is an ellipse."""
    m8 = mask.view(np.uint8)
    bx, by, bw, bh = cv2.boundingRect(m8)
    if bw < 2 or bh < 2:
        return 1.0
    ys, xs = np.mgrid[0:mask.shape[0], 0:mask.shape[1]]
    cx, cy = bx + 0.5 * bw, by + 0.5 * bh  # pixel centres at +0.5
    qx, qy = (xs + 0.5 - cx) / (0.5 * bw), (ys + 0.5 - cy) / (0.5 * bh)
    height = np.sqrt(np.clip(1.0 - qx * qx - qy * qy, 0.0, None))
    window = (np.abs(xs + 0.5 - cx) <= half[0]) & (np.abs(ys + 0.5 - cy) <= half[1])
    core = (cv2.erode(m8, _CORE) > 0) & window
    whole = float(height[mask].mean())
    if not core.any() or whole <= 0.0:
        return 1.0
    return float(height[core].mean()) / whole
