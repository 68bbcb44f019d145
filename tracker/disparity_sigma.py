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

import cv2
import numpy as np
from numpy.typing import NDArray

BoolA = NDArray[np.bool_]
COLUMNS, ROWS = 4, 2
MIN_PARTS = 5


def grid_parts(mask: BoolA, centre: tuple[float, float], half: tuple[int, int]) -> list[BoolA]:
    """The mask cut into COLUMNS x ROWS parts over the window of half size `half` (px, x and y) about
    `centre` (x, y, box pixels): the part of the mask the matcher uses (tracker.verify: a large object is
    matched on a central window), parts without pixels left out."""
    _, _, bw, bh = cv2.boundingRect(mask.view(np.uint8))
    hx, hy = min(half[0], bw / 2.0), min(half[1], bh / 2.0)
    xs = np.linspace(centre[0] - hx, centre[0] + hx, COLUMNS + 1)
    ys = np.linspace(centre[1] - hy, centre[1] + hy, ROWS + 1)
    parts = []
    for j in range(ROWS):
        for i in range(COLUMNS):
            part = np.zeros_like(mask)
            r0, r1 = max(int(round(ys[j])), 0), max(int(round(ys[j + 1])), 0)
            c0, c1 = max(int(round(xs[i])), 0), max(int(round(xs[i + 1])), 0)
            part[r0:r1, c0:c1] = mask[r0:r1, c0:c1]
            if part.any():
                parts.append(part)
    return parts


def scatter_sigma(disparities: list[float]) -> float:
    """The standard error of the mean of the parts' disparities (px), s / √n; 0 with fewer than MIN_PARTS
    (too few to tell: the matcher's own σ then stands)."""
    n = len(disparities)
    if n < MIN_PARTS:
        return 0.0
    return float(np.std(disparities, ddof=1) / np.sqrt(n))
