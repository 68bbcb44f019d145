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

`matched_factor` is the depth of a sphere's centre behind the face its disparity measures (the pixels
matched, seen in perspective), over what SolidPrior's ρ puts there; the centre's depth behind the face and
that depth's 1-σ are scaled by it (SolidPrior.behind_face_px, `matched`). Perspective counts at close range
on its own: seen from 10 radii a sphere's face lies 0.72 R before its centre, not 2R/3, and the prior's
extent is measured at the face's depth, 7 % nearer than the centre's. Orthographic (the window and the core
alone), discs 14, 35, 72 and 120 px across predict a disparity 0.17, 0.21, 1.28 and 2.92 % over the whole
face's; measured on approach:body at those widths 0.28, 0.16-0.21, 1.12 and 2.59 %. With the window and the
core alone the ball's range bias was -0.84 % at 2-4 m; with perspective too, -0.08 to +0.27 % (seeds 0-2),
and -0.02 % over the run (2026-12-06, docs/evaluation.md). A piece of a body seen upright whole before (a
person's part beside what hides the rest) keeps the factor 1: it is no sphere (tracker.pipeline).
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.strips import CORE, MATCH_HALF

BoolA = NDArray[np.bool_]


def matched_factor(mask: BoolA, f_px: float, ratio: float = 2.0 / 3.0,
                   half: tuple[int, int] = MATCH_HALF) -> float:
    """k: the depth of the sphere's centre behind the face its disparity measures, over SolidPrior's for a
    round body (ρ/2 · e at the face's depth, e = the outline's smaller extent; ρ = `ratio`, SolidPrior.ratio,
    2/3 for a sphere). The outline `mask` ((h, w) bool over its box, raw left pixels) is taken as the image
    of the sphere the prior supposes, seen from distance D: its angular radius a, tan a = e / 2f (f_px the
    focal length), so R = D sin a. Each pixel at normalised radius q (an ellipse on the box) looks along a
    ray θ off the centre's, tan θ = q tan a, which meets the sphere at depth z = (cos θ - √(sin²a -
    sin²θ)) cos θ D. The disparity matched is the mean of 1/z over the pixels matched (the core, eroded by
    tracker.strips.CORE, within the central window of half size `half`, px, about the box centre): the
    face at Z_m = 1 / mean(1/z). The centre lies D - Z_m behind it, where the prior puts ρ tan a · Z_m:
    k = (D - Z_m) / (ρ tan a Z_m). At a small angle, with the whole outline matched and ρ = 2/3, k = 1
    (the face's mean 2R/3 before the centre); a near ball's middle, its core and perspective (a near
    sphere's face lies more than 2R/3 before its centre, and the prior's extent is taken at the face's
    depth, not the centre's) raise it. 1 where nothing of the core lies in the window."""
    m8 = mask.view(np.uint8)
    bx, by, bw, bh = cv2.boundingRect(m8)
    if bw < 2 or bh < 2 or f_px <= 0:
        return 1.0
    ys, xs = np.mgrid[0:mask.shape[0], 0:mask.shape[1]]
    cx, cy = bx + 0.5 * bw, by + 0.5 * bh  # pixel centres at +0.5
    qx, qy = (xs + 0.5 - cx) / (0.5 * bw), (ys + 0.5 - cy) / (0.5 * bh)
    window = (np.abs(xs + 0.5 - cx) <= half[0]) & (np.abs(ys + 0.5 - cy) <= half[1])
    core = (cv2.erode(m8, CORE) > 0) & window
    if not core.any():
        return 1.0
    tan_a = 0.5 * float(min(bw, bh)) / f_px  # the prior's extent e
    sin_a = tan_a / float(np.sqrt(1.0 + tan_a * tan_a))
    q = np.minimum(np.sqrt(qx[core] ** 2 + qy[core] ** 2), 1.0)
    theta = np.arctan(q * tan_a)
    z = (np.cos(theta) - np.sqrt(np.clip(sin_a**2 - np.sin(theta) ** 2, 0.0, None))) * np.cos(theta)  # D = 1
    z_m = 1.0 / float(np.mean(1.0 / z))
    return (1.0 - z_m) / (ratio * tan_a * z_m)
