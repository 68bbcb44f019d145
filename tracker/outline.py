"""How far off the centroid of eq. (10) may lie because its outline is drawn by warping (issue 12 item 1).

While the cameras are still, the left temporal model draws a tracked object's outline pixel by pixel against
the background it has learnt (tracker.masks.temporal_outline). While they move there is no such model and
the outline is the stereo verification's (eq. 9 both ways, the right image warped onto the left through the
background's disparity and again at the object's): each pixel of its edge is in or out by the warp's
interpolation, the background disparity's error and the threshold ε against the sensor noise. An edge pixel
put in or left out moves the centroid by (its position - the centroid) / the area; for errors of σ_b px
each, independent from pixel to pixel along the edge,

    σ_cx² = σ_bx² Σ_edge (x_i - c_x)² / A²,   σ_cy² = σ_by² Σ_edge (y_i - c_y)² / A²   (px², A in px).

σ_b is larger across the rows than along the columns: warping shifts the image along the rows only, so the
warp's errors move the left and right edges; the top and bottom edges see the threshold alone. Measured on
the pan scene (240 frames, cameras moving at 6.7°/s rms; the eval's true visible outline): the centroid of
the warped outline was off by 0.137 px rms across and 0.053 px along the columns, which this model met
with σ_bx = 1.0 px and σ_by = 0.4 px (it made the azimuth's normalised error there 2.6 times its 1-σ).
Measured again later (2026-11-29, the plates of pan and manoeuvre, 240 and 294 frames, the edge
quantisation term of tracker.segmentation in quadrature): off by 0.133 and 0.137 px rms across, 0.047 and
0.043 px along the columns; the least-squares σ_b over both scenes are 1.07 px across (1.0 kept) and
0.23 px along (0.27 and 0.20 apart), which σ_by now is (0.4 made the plates' elevation NEES 0.54 and 0.44).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

BoolA = NDArray[np.bool_]
_CROSS = cv2.getStructuringElement(cv2.MORPH_CROSS, (3, 3))


@dataclass(frozen=True)
class OutlineConfig:
    """edge_px: the 1-σ (px) of a warped outline's edge pixels (x: across the rows' direction of warping,
    y: along the columns); see the module's docstring."""

    edge_px: tuple[float, float] = (1.0, 0.23)


def warped_outline_sigma_px(mask: BoolA, cfg: OutlineConfig) -> tuple[float, float]:
    """The centroid's 1-σ (px, x and y) from the errors of a warped outline's edge pixels: σ_b times the
    root sum of the squared distances of the mask's edge pixels (those with a 4-neighbour outside it) from
    its centroid, over its area."""
    m8 = mask.view(np.uint8)
    ys, xs = np.nonzero(mask)
    if xs.size == 0:
        return 0.0, 0.0
    edge = mask & (cv2.erode(m8, _CROSS, borderType=cv2.BORDER_CONSTANT, borderValue=0) == 0)
    ey, ex = np.nonzero(edge)
    a = float(xs.size)
    sx = float(np.sqrt(np.sum(np.square(ex - xs.mean())))) / a
    sy = float(np.sqrt(np.sum(np.square(ey - ys.mean())))) / a
    return cfg.edge_px[0] * sx, cfg.edge_px[1] * sy
