"""Full-resolution verification of a candidate and its centroid (paper eq. 9 both ways, eq. 10).

Occlusion shadows: with the left image as key, an object also shows up where the right camera sees it at
the background disparity, a "ghost" displaced by (d_object - d_background). With the right image as key the
ghost falls on the other side. Warping the right-key mask into the left image at the object's disparity
and intersecting it with the left-key mask keeps the object and removes both ghosts (for convex objects
exactly; Ivanov, Bobick and Liu's verification by warping in both directions).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.detect import Box, StereoSubtractor
from tracker.frames import StereoFrame
from tracker.rectify import Rectifier
from tracker.stereo import match_region

U8 = NDArray[np.uint8]
F64 = NDArray[np.float64]
BoolA = NDArray[np.bool_]


@dataclass(frozen=True)
class Blob:
    """A verified object in one frame. box: raw-left pixels (x0, y0, x1, y1); mask: bool (y1-y0, x1-x0);
    centroid_raw: eq. (10) in raw left pixels; centroid_rect: the same pixels' centroid in rectified
    coordinates; disparity, disparity_sigma, bg_disparity in px (rectified)."""

    box: Box
    mask: BoolA
    area: int
    centroid_raw: F64
    centroid_rect: F64
    disparity: float
    disparity_sigma: float
    bg_disparity: float
    score: float
    gain: float = 1.0


def _key_mask(key: U8, other: U8, mx: NDArray[np.float32], my: NDArray[np.float32], valid: BoolA,
              eps: int, floor: U8 | None) -> BoolA:
    """eq. (9) for the pixels of a box: |Γ - Θ(x', y')| > ε (+ the temporal floor B)."""
    ref = cv2.remap(other, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    resid = cv2.absdiff(key, ref)
    if floor is not None:
        resid = cv2.subtract(resid, floor)
    return np.asarray((resid > eps) & valid)


_CLOSE = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))


def _largest(mask: BoolA, close: bool = False) -> BoolA:
    """The largest 8-connected component with its holes filled; with `close`, narrow channels into the
    holes are sealed first (a morphological closing), so the holes are filled too."""
    m8 = mask.astype(np.uint8)
    if close:
        m8 = np.asarray(cv2.morphologyEx(m8, cv2.MORPH_CLOSE, _CLOSE), np.uint8) | m8
    contours, _ = cv2.findContours(m8, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    if not contours:
        return np.zeros_like(mask)
    best = max(contours, key=cv2.contourArea)
    out = np.zeros(mask.shape, np.uint8)
    cv2.drawContours(out, [best], -1, 1, thickness=cv2.FILLED)
    return out.astype(bool)


_RING = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (9, 9))
_NEAR = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))


def _temporal_outline(key: U8, bg: NDArray[np.float32], solid: BoolA, eps: int) -> tuple[BoolA, float]:
    """The object's exact outline from the temporal model, inside the stereo-verified region.

    The global gain g is the median ratio Γ/B on the box's background ring; then |Γ - g B| > ε.
    Returns the mask and g (1.0 when the ring is too small)."""
    s8 = solid.astype(np.uint8)
    near = cv2.dilate(s8, _NEAR) > 0  # the stereo outline is good to a pixel or two
    ring = (cv2.dilate(s8, _RING) == 0) & (bg > 8.0)
    g = float(np.median(key[ring] / bg[ring])) if int(ring.sum()) >= 20 else 1.0
    diff = np.abs(key.astype(np.float32) - np.float32(g) * bg) > eps
    return _largest(diff & near, close=True), g


class Verifier:
    """Turns candidate boxes into verified Blobs (or nothing)."""

    def __init__(self, sub: StereoSubtractor, rect: Rectifier):
        self.sub = sub
        self.rect = rect
        self.cfg = sub.cfg

    def verify(self, frame: StereoFrame, box: Box) -> Blob | None:
        cfg, rect = self.cfg, self.rect
        x0, y0, x1, y1 = box
        cm = self.sub.correspondence(0, frame.gimbal, box)
        m_left = _key_mask(frame.left[y0:y1, x0:x1], frame.right, cm.map_x, cm.map_y, cm.valid,
                           cfg.epsilon, self.sub.floor_at(box))
        if int(m_left.sum()) < cfg.min_area_px:
            return None
        # where the object overlaps its own ghost, Γ and Θ both show the object and may agree: holes
        m_left = _largest(m_left, close=True)
        coarse = self._match(frame, box, m_left, None)
        if coarse is None:
            return None
        d0 = coarse[0]
        obj = _largest(m_left & self._right_key_at(frame, box, d0))
        bg = self.sub.left_background(frame.gimbal)
        gain = 1.0
        if bg is not None:
            obj, gain = _temporal_outline(frame.left[y0:y1, x0:x1], bg[y0:y1, x0:x1], obj, cfg.epsilon)
        area = int(obj.sum())
        if area < cfg.min_area_px:
            return None
        fine = self._match(frame, box, obj, d0)
        if fine is None:
            return None
        d, sigma, score = fine
        ys, xs = np.nonzero(obj)
        rc = rect.rect_of_raw[0][y0:y1, x0:x1][ys, xs].astype(np.float64)
        a = rect.area_of_raw[y0:y1, x0:x1][ys, xs].astype(np.float64)
        c_rect = (a[:, None] * rc).sum(axis=0) / a.sum()  # eq. (10) in rectified coordinates
        c_raw = np.array([xs.mean() + x0, ys.mean() + y0])  # eq. (10), c(i, j) = the object mask
        d_bg = float(np.median(cm.disparity[ys, xs]))
        if d < d_bg * (1.0 + cfg.min_depth_gap) + cfg.min_disparity_gap_px:
            return None  # not in front of the background: a misregistered background patch
        return Blob(box, obj, area, c_raw, c_rect, d, sigma, d_bg, score, gain)

    def _right_key_at(self, frame: StereoFrame, box: Box, d: float) -> BoolA:
        """The right-key mask of eq. (9), sampled at the left box's pixels shifted by disparity d."""
        rect = self.rect
        x0, y0, x1, y1 = box
        rc = rect.rect_of_raw[0][y0:y1, x0:x1].astype(np.float64)
        ur, vr = rect.raw_of_rect(1, rc[..., 0] - d, rc[..., 1])  # raw right position of each left pixel
        w, h = rect.rig.right.size
        bx0, by0 = max(int(np.floor(ur.min())) - 1, 0), max(int(np.floor(vr.min())) - 1, 0)
        bx1, by1 = min(int(np.ceil(ur.max())) + 2, w), min(int(np.ceil(vr.max())) + 2, h)
        if bx0 >= bx1 or by0 >= by1:
            return np.zeros((y1 - y0, x1 - x0), bool)
        rbox = (bx0, by0, bx1, by1)
        cm = self.sub.correspondence(1, frame.gimbal, rbox)
        floor = self.sub.static_floor(1, frame.gimbal, rbox)
        m_right = _largest(_key_mask(frame.right[by0:by1, bx0:bx1], frame.left, cm.map_x, cm.map_y,
                                     cm.valid, self.cfg.epsilon, floor), close=True).astype(np.float32)
        sampled = cv2.remap(m_right, (ur - bx0).astype(np.float32), (vr - by0).astype(np.float32),
                            cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0.0)
        return np.asarray(sampled >= 0.5)

    def _match(self, frame: StereoFrame, box: Box, obj: BoolA, d0: float | None
               ) -> tuple[float, float, float] | None:
        """Disparity of the object region along the epipolar lines, in rectified coordinates."""
        rect = self.rect
        x0, y0, _x1, _y1 = box
        ys, xs = np.nonzero(obj)
        if xs.size < 8:
            return None
        rc = rect.rect_of_raw[0][y0:_y1, x0:_x1][ys, xs]
        w, h = rect.rig.left.size
        rx0, ry0 = int(np.floor(rc[:, 0].min())), int(np.floor(rc[:, 1].min()))
        rx1, ry1 = int(np.ceil(rc[:, 0].max())) + 1, int(np.ceil(rc[:, 1].max())) + 1
        dmax = min(self.cfg.max_disparity, max(rx0 - 3, 0))
        sx0 = rx0 - dmax - 2
        if dmax < 3 or sx0 < 0 or rx1 + 2 > w or ry0 < 0 or ry1 > h:
            return None
        strip = (sx0, ry0, rx1 + 2, ry1)
        left_r = rect.rectify(frame.left, 0, strip)
        right_r = rect.rectify(frame.right, 1, strip)
        # the object mask in rectified coordinates, shrunk by about a pixel so that no background
        # next to the outline enters the match
        mx, my = rect.maps[0]
        mmx = mx[ry0:ry1, rx0:rx1] - np.float32(x0)
        mmy = my[ry0:ry1, rx0:rx1] - np.float32(y0)
        wgt = cv2.remap(obj.astype(np.float32), mmx, mmy, cv2.INTER_LINEAR,
                        borderMode=cv2.BORDER_CONSTANT, borderValue=0.0)
        wgt = cv2.erode((wgt > 0.99).astype(np.uint8), np.ones((3, 3), np.uint8))
        if int(wgt.sum()) < 8:
            wgt = (cv2.remap(obj.astype(np.float32), mmx, mmy, cv2.INTER_LINEAR) > 0.5).astype(np.uint8)
        m = match_region(left_r, right_r, wgt, rx0 - sx0, 0, dmax + 2, d0)
        if m is None:
            return None
        return m.disparity, m.sigma, m.score
