"""The outline's rim recovered about an object verified in a box of a frame (tracker.verify): the pictures
tracker.rim's tests compare, cropped and warped from the frame, the background's map and the temporal model."""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.bgdepth import CorrespondenceMap
from tracker.frames import StereoFrame
from tracker.limbs import limbs_closed
from tracker.rectify import Rectifier
from tracker.rim import Pictures, RimConfig, recover_rim, recover_rim_keys
from tracker.strips import whole_outline

U8 = NDArray[np.uint8]
F32 = NDArray[np.float32]
I32 = NDArray[np.int32]
BoolA = NDArray[np.bool_]
Box = tuple[int, int, int, int]

DEFAULT_RIM = RimConfig()


class RimRecovery:
    """recover_rim (cameras still) and recover_rim_keys (always) for an object verified in a box of a
    frame (tracker.verify)."""

    def __init__(self, cfg: RimConfig, rect: Rectifier, epsilon: int):
        self.cfg = cfg
        self.rect = rect
        self.epsilon = epsilon

    def recover(self, frame: StereoFrame, box: Box, cm: CorrespondenceMap, obj: BoolA, d: float, free: BoolA,
                gain: float = 1.0, model: tuple[F32, F32] | None = None) -> BoolA:
        """The object's mask (bool, over the box) with its rim recovered, worked out over its bounding box
        grown by the band and the window: recover_rim with the cameras still (`model` given), then
        recover_rim_keys, then for an upright outline (tracker.strips.whole_outline)
        tracker.limbs.limbs_closed. d: its disparity (px); cm: the background's correspondences over the
        box; model: the left temporal background B and its deviation D (full image) at global gain g =
        `gain`, None while the cameras move; free: where it may grow (no other object's pixels, none the
        temporal outline left out as changed). With the cameras still, pixels whose background moves (3 g D
        ≥ ε: foliage) do not join: no hypothesis holds. The pictures are sampled once for all three."""
        (sx0, sy0, sx1, sy1), (x0, y0, x1, y1), right_obj, right_bg = self._pictures(frame, box, cm, obj, d)
        left = frame.left[y0:y1, x0:x1]
        allowed = cm.valid[sy0:sy1, sx0:sx1] & free[sy0:sy1, sx0:sx1]
        part, g_bg = obj[sy0:sy1, sx0:sx1], None
        if model is not None:
            bg, dev = model[0][y0:y1, x0:x1], model[1][y0:y1, x0:x1]
            allowed &= np.float32(3.0 * gain) * dev < np.float32(self.epsilon)
            g_bg = np.asarray(cv2.convertScaleAbs(bg, alpha=gain), np.uint8)  # g B, rounded to grey levels
        pictures = Pictures(left, right_obj, right_bg, g_bg, self.cfg.window_px)
        if model is not None:
            part = recover_rim(part, pictures, allowed, self.cfg)
        shift = np.float32(d) - cm.disparity[sy0:sy1, sx0:sx1]
        may_join = allowed.copy()  # where an upright outline's limbs may be closed (tracker.limbs)
        # where the background lies about as deep as the object (the ground at a walker's feet), the
        # object's pictures match it as well: no test tells them apart there
        allowed &= shift > np.float32(self.cfg.slant * d + 1.0)
        # nor where a window would reach past the pictures (the sums there see a mirrored border)
        allowed = off_edges(allowed, self.cfg.window_px // 2)
        sub = (x0, y0, x1, y1)
        bx, by = self.rect.left_along(sub, -shift)  # Δd to the left along the rectified row, in raw pixels
        left_bg = np.asarray(cv2.remap(frame.left, bx, by, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE),
                             np.uint8)
        fx, fy = self.rect.left_along(sub, shift)
        part = recover_rim_keys(part, pictures, left_bg, in_part(fx, fy, sub), in_part(bx, by, sub), allowed,
                                self.cfg, self.epsilon, shift >= np.float32(self.cfg.window_px))
        if whole_outline(part):  # upright: a person's
            part = limbs_closed(part, pictures, may_join)
        out = obj.copy()
        out[sy0:sy1, sx0:sx1] = part
        return out

    def _pictures(self, frame: StereoFrame, box: Box, cm: CorrespondenceMap, obj: BoolA, d: float
                  ) -> tuple[Box, Box, list[U8], U8]:
        """The part of the box worked on (the object's bounding box grown by the band and the window; in the
        box's and in image pixels), the right image there at the object's disparity and at its slant's
        (d (1 ± slant)), and at the background's."""
        bx, by, bw, bh = cv2.boundingRect(obj.view(np.uint8))
        m = self.cfg.band_px + self.cfg.window_px
        h, w = obj.shape
        sx0, sy0, sx1, sy1 = max(bx - m, 0), max(by - m, 0), min(bx + bw + m, w), min(by + bh + m, h)
        x0, y0, x1, y1 = box[0] + sx0, box[1] + sy0, box[0] + sx1, box[1] + sy1
        right_obj = [self.rect.right_image_at(frame.right, (x0, y0, x1, y1), d * (1.0 + k))
                     for k in ((0.0, -self.cfg.slant, self.cfg.slant) if self.cfg.slant else (0.0,))]
        right_bg = cm.crop((sx0, sy0, sx1, sy1)).warp(frame.right)
        return (sx0, sy0, sx1, sy1), (x0, y0, x1, y1), right_obj, right_bg


def off_edges(mask: BoolA, half: int) -> BoolA:
    """The mask (h, w) with its outer `half` rows and columns on each side cleared (none for half 0)."""
    out = np.zeros_like(mask)
    h, w = mask.shape
    out[half:h - half, half:w - half] = mask[half:h - half, half:w - half]
    return out


def in_part(x: F32, y: F32, part: Box) -> I32:
    """(h, w, 2) row and column, in the part (x0, y0, x1, y1), of raw positions x, y (nearest pixel)."""
    return np.stack([np.rint(y) - part[1], np.rint(x) - part[0]], axis=-1).astype(np.int32)
