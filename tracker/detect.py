"""Lighting-independent stereo background subtraction, paper eq. (9), fused with a temporal model.

Per frame:
1. Candidates, on every `stride`-th pixel: the left (key) image Γ is compared with the right (reference)
   image Θ warped by the background correspondence, m = |Γ(x, y) - Θ(x', y')| > ε + B(x, y), eq. (9).
   B is the temporal part: a per-pixel floor of the stereo residual that falls at once and rises slowly,
   so places where the background warp is imperfect (half-occlusions, aliasing) are learnt away, objects
   that stop merge into the background (within `absorb_s` for residuals up to 100 grey levels: under an
   object the floor rises one level every absorb_s·fps/100 frames), and a background that reappears is
   usable in the next frame. A global change of light scales Γ and Θ alike and leaves m unchanged; the
   two cameras' own exposures, which need not stay alike, are matched first (`balanced`, tracker.exposure).
2. Verification at full resolution inside each candidate's box (tracker.verify).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.bgdepth import BackgroundDepth, CorrespondenceMap
from tracker.boxes import stacked_joined
from tracker.exposure import ExposureBalance
from tracker.frames import GimbalState, StereoFrame, check_pair
from tracker.masks import change, strict_limit

U8 = NDArray[np.uint8]
Box = tuple[int, int, int, int]
_NEAR_OBJECTS = np.ones((5, 5), np.uint8)  # two grid cells (8 px at stride 4) about an object


def paint_masks(masks: list[tuple[Box, NDArray[np.bool_]]], row0: int, shape: tuple[int, int]
                ) -> NDArray[np.bool_]:
    """Object masks (box, mask) painted into a bool image of `shape` whose first row is image row `row0`."""
    out = np.zeros(shape, bool)
    for (x0, y0, x1, y1), m in masks:
        a, b = max(y0, row0), min(y1, row0 + shape[0])
        if a < b:
            out[a - row0:b - row0, x0:x1] |= m[a - y0:b - y0]
    return out


# of an object's rows: the margin about it the temporal background is not updated in. 4 % made endless:body
# worse than 6 % (identity switches 8 against 4, azimuth RMSE against the seen surface 0.268 against
# 0.147°); the other bodies differ by under 0.01° between the two
MARGIN_REL = 0.06


def object_margin(box: Box, mask: NDArray[np.bool_], size: tuple[int, int], rows: tuple[int, int]
                  ) -> tuple[Box, NDArray[np.bool_]] | None:
    """An object's mask (over `box`) grown by r = max(2, MARGIN_REL x the rows it spans) px (a disc), over
    its box grown by r and clipped to the image (`size`: width, height) and to the image rows `rows` (a, b):
    what the temporal background leaves alone about it there. Only the mask's rows within r of those are
    dilated (the background is updated a stripe at a time). None where the mask is empty or its grown box
    misses the rows."""
    span = np.flatnonzero(mask.any(axis=1))
    if span.size == 0:
        return None
    r = max(2, int(round(MARGIN_REL * (span[-1] - span[0] + 1))))
    x0, y0, x1, y1 = box
    w, h = size
    a, b = max(rows[0], y0 - r, 0), min(rows[1], y1 + r, h)
    if a >= b:
        return None
    ma, mb = max(a - r, y0), min(b + r, y1)  # the mask's rows that reach rows a..b
    disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1))
    sub = mask[ma - y0:mb - y0].astype(np.uint8)
    grown = cv2.dilate(cv2.copyMakeBorder(sub, r, r, r, r, cv2.BORDER_CONSTANT, value=0), disc)
    gx0, gx1 = max(x0 - r, 0), min(x1 + r, w)  # grown's row 0 is image row ma - r, its column 0 x0 - r
    crop = grown[a - (ma - r):b - (ma - r), gx0 - (x0 - r):gx1 - (x0 - r)]
    return (gx0, a, gx1, b), np.asarray(crop > 0)


@dataclass(frozen=True)
class DetectorConfig:
    """epsilon: eq. (9) threshold ε in grey levels; stride: candidate-search subsampling; min_area_px:
    smallest object (full-resolution pixels); absorb_s: how long a stopped object takes to merge into the
    background; margin_px: box padding; min_depth_gap: an object's disparity must exceed the background's
    by this fraction plus `min_disparity_gap_px`. moving_min_cells: while the cameras move, a candidate
    needs this many stride cells above the threshold unless a track is predicted inside its box (a moving
    view samples the background's edges at new sub-pixel phases, which leaves isolated residuals; a new
    object must then cover about moving_min_cells · stride² pixels to be picked up). near_m: the nearest
    range (m) of the background: it bounds the background's disparity search to f·b / near_m.
    max_speed_mps: the fastest a tracked object's range changes (m/s): it bounds the search about the
    track's predicted disparity (tracker.region_match.RegionMatcher.search_radius)."""

    epsilon: int = 12
    stride: int = 4
    min_area_px: int = 16
    absorb_s: float = 20.0
    fps: float = 30.0
    margin_px: int = 6
    min_depth_gap: float = 0.04
    min_disparity_gap_px: float = 0.5
    max_disparity: int = 160
    moving_min_cells: int = 3
    near_m: float = 2.5
    max_speed_mps: float = 15.0

    def __post_init__(self) -> None:
        if not 1 <= self.epsilon <= 254:
            raise ValueError(f"epsilon must be in 1..254 grey levels, got {self.epsilon}")
        if self.stride not in (1, 2, 4):
            raise ValueError(f"stride must be 1, 2 or 4, got {self.stride}")
        if self.min_area_px < 1 or self.absorb_s <= 0 or self.fps <= 0:
            raise ValueError("min_area_px, absorb_s and fps must be positive")
        if not self.near_m > 0:
            raise ValueError(f"near_m must be a positive range in metres, got {self.near_m}")


class _LazyMap:
    """The full-resolution correspondence map of camera `key` at one pose, computed as boxes ask for it
    (the first frame at a new pose maps only what it verifies, not the whole image). `done` (H, W) marks
    the pixels mapped; a box maps the bounding box of its pixels not mapped yet (no rounding up to tiles:
    the many small boxes of a first frame at a new pose map little more than themselves)."""

    def __init__(self, bg: BackgroundDepth, key: int, gimbal: GimbalState | None):
        self.bg, self.key, self.gimbal = bg, key, gimbal
        w, h = bg.rect.rig.left.size
        self.size = (w, h)
        self.map = CorrespondenceMap(np.zeros((h, w), np.float32), np.zeros((h, w), np.float32),
                                     np.zeros((h, w), bool), np.zeros((h, w), np.float32), np.zeros((h, w), np.uint8))
        self.done = np.zeros((h, w), bool)

    def get(self, box: Box) -> CorrespondenceMap:
        x0, y0, x1, y1 = box
        todo = ~self.done[y0:y1, x0:x1]
        rows, cols = np.flatnonzero(todo.any(axis=1)), np.flatnonzero(todo.any(axis=0))
        if rows.size:  # map the bounding box of the missing pixels in one go
            fill = (x0 + int(cols[0]), y0 + int(rows[0]), x0 + int(cols[-1]) + 1, y0 + int(rows[-1]) + 1)
            self.map.paste(fill, self.bg.correspondence(self.key, self.gimbal, box=fill))
            self.done[fill[1]:fill[3], fill[0]:fill[2]] = True
        return self.map.crop(box)


@dataclass
class _PoseMaps:
    """Correspondence maps for one gimbal pose: low-res for candidates, full-res ones filled lazily."""

    pose: tuple[float, float]
    low: CorrespondenceMap
    low_fixed: NDArray[np.int16]
    valid_u8: U8
    half_fixed: NDArray[np.int16]  # low_fixed at every other point, for the exposure's samples
    full: dict[int, _LazyMap] = field(default_factory=dict)


def predictions_in(box: Box, hints: NDArray[np.float64] | None) -> int:
    """How many predicted track positions (x, y) (raw left pixels; hints (N, 2+)) lie inside the box."""
    return 0 if hints is None else sum(box[0] <= h[0] < box[2] and box[1] <= h[1] < box[3] for h in hints)


def holds_prediction(box: Box, hints: NDArray[np.float64] | None) -> bool:
    """Whether a predicted track position lies inside the box (`predictions_in`)."""
    return predictions_in(box, hints) > 0


@dataclass(frozen=True)
class Candidates:
    """Candidate boxes (raw left pixels, x0 y0 x1 y1), the number of stride cells above the threshold in
    each, the low-resolution residual image and whether the cameras moved since the last frame."""

    boxes: tuple[Box, ...]
    cells: tuple[int, ...]
    residual: U8
    moving: bool

    def worth_verifying(self, min_cells: int, hints: NDArray[np.float64] | None) -> tuple[Box, ...]:
        """The boxes to verify: all of them with the cameras still; while they move, those with at least
        min_cells cells or with a predicted track position (x, y) inside."""
        if not self.moving:
            return self.boxes
        return tuple(b for b, n in zip(self.boxes, self.cells, strict=True)
                     if n >= min_cells or holds_prediction(b, hints))


class StereoSubtractor:
    """Candidate stage of eq. (9) with the temporal residual floor B. `step(frame)` -> Candidates."""

    def __init__(self, bg: BackgroundDepth, config: DetectorConfig | None = None):
        self.bg = bg
        self.cfg = config or DetectorConfig()
        w, h = bg.rect.rig.left.size
        s = self.cfg.stride
        self.low_shape = ((h + s - 1) // s, (w + s - 1) // s)
        self.floor = np.zeros(self.low_shape, np.uint8)  # B, the temporal residual floor
        self._ones = np.ones(self.low_shape, np.uint8)
        self._maps: _PoseMaps | None = None
        self.exposure = ExposureBalance()
        self._objects_low: U8 | None = None  # the last frame's objects on the candidate grid, for `balanced`
        self._fg_every = max(1, round(self.cfg.absorb_s * self.cfg.fps / 100.0))
        self._count = 0
        self.moving = False
        self._frame_pose: tuple[float, float] | None = None  # pose of the last frame stepped
        self._pending: tuple[U8, bool] | None = None
        # temporal model per pose: background B and mean absolute deviation D, at gain 1
        self.left_bg: dict[tuple[float, float], tuple[NDArray[np.float32], NDArray[np.float32]]] = {}
        self._stripe = 0
        # per pose: rows of the left image whose deviation D has been learnt (updated often enough)
        self.left_learnt: dict[tuple[float, float], NDArray[np.int32]] = {}

    def reconfigure(self, config: DetectorConfig) -> None:
        """Use new settings from the next frame on; the stride (the shape of the candidate grid) is fixed."""
        if config.stride != self.cfg.stride:
            raise ValueError(f"stride cannot change while running ({self.cfg.stride} -> {config.stride})")
        self.cfg = config
        self._fg_every = max(1, round(config.absorb_s * config.fps / 100.0))

    # -- correspondence maps ----------------------------------------------------------------------
    def maps(self, gimbal: GimbalState | None) -> _PoseMaps:
        g = gimbal or GimbalState()
        pose = self._pose(g)
        if self._maps is None or self._maps.pose != pose:
            low = self.bg.correspondence(0, g, step=self.cfg.stride)
            mx = np.where(low.valid, low.map_x, -10.0).astype(np.float32)
            fixed = cv2.convertMaps(mx, low.map_y, cv2.CV_16SC2, nninterpolation=True)
            nearest = np.asarray(fixed[0], np.int16)  # (h, w, 2) nearest pixels
            self._maps = _PoseMaps(pose, low, nearest, low.valid.astype(np.uint8) * np.uint8(255),
                                   np.ascontiguousarray(nearest[::2, ::2]))
        return self._maps

    def reset_maps(self) -> None:
        """Forget cached correspondence maps (after the background geometry changed)."""
        self._maps = None

    def restart_floor(self) -> None:
        """Take the residual floor from the learnt background again at the next frame (after a relearn)."""
        self._frame_pose = None

    def correspondence(self, key: int, gimbal: GimbalState | None, box: Box) -> CorrespondenceMap:
        """Full-resolution correspondence for the pixels in `box` of camera `key`. While the pose stays,
        the map is kept and filled in tiles as boxes need them; while it moves, only the box is mapped."""
        if self.moving:  # the pose changes every frame
            return self.bg.correspondence(key, gimbal, box=box)
        pm = self.maps(gimbal)
        full = pm.full.get(key)
        if full is None:
            full = pm.full[key] = _LazyMap(self.bg, key, gimbal)
        return full.get(box)

    def prime(self, frame: StereoFrame) -> None:
        """Start the temporal model from an empty-scene pair at its pose: the background image B. The
        next frame counts as the first (not "moving"); `step` seeds the residual floor from the survey
        and maps the correspondences at whatever pose that frame has (not at every survey pose)."""
        pose = self._pose(frame.gimbal)
        self.left_bg[pose] = (frame.left.astype(np.float32), np.zeros(frame.left.shape, np.float32))
        self.left_learnt[pose] = np.zeros(frame.left.shape[0], np.int32)
        self._frame_pose = None

    def pose_of(self, gimbal: GimbalState | None) -> tuple[float, float]:
        """The key of a gimbal pose in the per-pose models: (pan, tilt) in degrees, rounded to 1e-4."""
        return self._pose(gimbal)

    @staticmethod
    def _pose(gimbal: GimbalState | None) -> tuple[float, float]:
        g = gimbal or GimbalState()
        return (round(g.pan_deg, 4), round(g.tilt_deg, 4))

    def left_background(self, gimbal: GimbalState | None
                        ) -> tuple[NDArray[np.float32], NDArray[np.float32]] | None:
        """The left camera's temporal model at this pose: background B and its mean absolute deviation D
        (grey levels at gain 1; (H, W) float32 each). None while the cameras move."""
        return None if self.moving else self.left_bg.get(self._pose(gimbal))

    def learnt_rows(self, gimbal: GimbalState | None, updates: int) -> NDArray[np.bool_] | None:
        """Rows (H,) of the left temporal model at this pose whose D has had `updates` updates or more
        (a model primed from one pair knows no deviation yet: swaying foliage would look like change)."""
        n = self.left_learnt.get(self._pose(gimbal))
        return None if n is None else np.asarray(n >= updates)

    def update_left_background(self, frame: StereoFrame, objects: list[tuple[Box, NDArray[np.bool_]]],
                               gain: float, stripes: int = 24, alpha: float = 0.3) -> None:
        """Adapt the temporal background B ← B + α (Γ/g - B) on one horizontal stripe per frame (each
        row every `stripes` frames), away from objects and a margin about them (object_margin: an outline
        that missed a rim or a limb must not teach the model the object, which would then show as a ghost
        where it was); g is the global gain of this frame. Where Γ/g is unlike B past the strict limit
        (ε/g + 3 D) the rate is α/10: an object no outline covered this frame (missed, or taken into
        another's) is not learnt in one pass, while what stays there long (a parked car) still is."""
        model = self.left_background(frame.gimbal)
        if model is None:
            return
        bg, dev = model
        h = bg.shape[0]
        k = self._stripe % stripes
        self._stripe += 1
        y0, y1 = k * h // stripes, (k + 1) * h // stripes
        self.left_learnt[self._pose(frame.gimbal)][y0:y1] += 1
        cur = frame.left[y0:y1].astype(np.float32) * np.float32(1.0 / max(gain, 1e-3))
        grown = [g for b, m in objects if (g := object_margin(b, m, (bg.shape[1], h), (y0, y1))) is not None]
        keep = paint_masks(grown, y0, (y1 - y0, bg.shape[1])) if grown else None
        # a pixel unlike the background (|Γ - g B| past the strict limit ε + 3 g D) adapts slowly: an object
        # missed this frame would otherwise be learnt in one pass (D jumps by α |Γ/g - B|, the limit with it)
        unlike = change(frame.left[y0:y1], bg[y0:y1], gain) > strict_limit(dev[y0:y1], gain, self.cfg.epsilon)
        a = np.where(unlike, np.float32(alpha * 0.1), np.float32(alpha))
        new_dev = dev[y0:y1] + a * (np.abs(cur - bg[y0:y1]) - dev[y0:y1])  # D ← D + α(|Γ/g - B| - D)
        new_bg = bg[y0:y1] + a * (cur - bg[y0:y1])  # B ← B + α(Γ/g - B)
        dev[y0:y1] = new_dev if keep is None else np.where(keep, dev[y0:y1], new_dev)
        bg[y0:y1] = new_bg if keep is None else np.where(keep, bg[y0:y1], new_bg)

    def floor_at(self, box: Box) -> U8:
        """The temporal floor B upsampled (nearest) to the full-resolution pixels of `box`."""
        s = self.cfg.stride
        x0, y0, x1, y1 = box
        sub = self.floor[y0 // s:(y1 + s - 1) // s, x0 // s:(x1 + s - 1) // s]
        up = (cv2.resize(sub, (sub.shape[1] * s, sub.shape[0] * s), interpolation=cv2.INTER_NEAREST)
              if s > 1 else sub)
        oy, ox = y0 - (y0 // s) * s, x0 - (x0 // s) * s
        return np.asarray(up[oy:oy + y1 - y0, ox:ox + x1 - x0])

    # -- the step ---------------------------------------------------------------------------------
    def _checked(self, frame: StereoFrame) -> None:
        check_pair(frame.left, frame.right)
        if frame.left.shape[::-1] != self.bg.rect.rig.left.size:
            raise ValueError(f"frame size {frame.left.shape[::-1]} does not match the rig's "
                             f"{self.bg.rect.rig.left.size}")

    def balanced(self, frame: StereoFrame) -> StereoFrame:
        """The frame with its right image's exposure matched to the left's (tracker.exposure), measured on
        every other point of the candidate grid (about 4,800 at 640 x 480) at this pose's background
        correspondence; the frame itself where they match."""
        self._checked(frame)
        pm, s = self.maps(frame.gimbal), 2 * self.cfg.stride
        key = frame.left[::s, ::s]
        ref = cv2.remap(frame.right, pm.half_fixed, None, cv2.INTER_NEAREST)  # type: ignore[call-overload, unused-ignore]
        valid = pm.valid_u8
        if self._objects_low is not None:  # not on the last frame's objects, nor 8 px about them
            valid = np.asarray(cv2.bitwise_and(valid, cv2.bitwise_not(cv2.dilate(self._objects_low, _NEAR_OBJECTS))),
                               np.uint8)
        ratio = self.exposure.step(key, np.asarray(ref, np.uint8), valid[::2, ::2])
        return replace(frame, right=self.exposure.balanced(frame.right, ratio)) if ratio.applied else frame

    def step(self, frame: StereoFrame) -> Candidates:
        self._checked(frame)
        prev, pm = self._frame_pose, self.maps(frame.gimbal)
        moving = prev is not None and prev != pm.pose
        if prev != pm.pose:  # new pose: start from the survey's floor there (the old one is misplaced)
            self.floor = pm.low.floor.copy()
        self._frame_pose = pm.pose
        self.moving = moving
        s = self.cfg.stride
        key = frame.left[::s, ::s] if s > 1 else frame.left
        ref = cv2.remap(frame.right, pm.low_fixed, None, cv2.INTER_NEAREST)  # type: ignore[call-overload, unused-ignore]
        resid = np.asarray(cv2.absdiff(key, ref), np.uint8)  # |Γ(x, y) - Θ(x', y')|, eq. (9)
        excess = cv2.subtract(resid, self.floor)
        fg = np.asarray(cv2.threshold(excess, self.cfg.epsilon, 255, cv2.THRESH_BINARY)[1], np.uint8)
        cv2.bitwise_and(fg, pm.valid_u8, dst=fg)
        boxes, cells = self._boxes(fg)
        cv2.min(self.floor, resid, dst=self.floor)  # the floor falls at once
        self._pending = (resid, moving)
        return Candidates(boxes, cells, resid, moving)

    def _boxes(self, fg: U8) -> tuple[tuple[Box, ...], tuple[int, ...]]:
        """Boxes around groups of candidate cells (raw pixels, with a margin) and the cells in each."""
        s, m = self.cfg.stride, self.cfg.margin_px
        if cv2.countNonZero(fg) == 0:
            return (), ()
        grown = cv2.dilate(fg, np.ones((3, 3), np.uint8))
        contours, _ = cv2.findContours(grown, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
        h, w = self.bg.rect.rig.left.size[1], self.bg.rect.rig.left.size[0]
        min_low = max(2, self.cfg.min_area_px // (s * s) // 2)
        out, cells = [], []
        for c in contours:
            x, y, bw, bh = cv2.boundingRect(c)
            if bw * bh < min_low:
                continue
            out.append((max(x * s - m, 0), max(y * s - m, 0), min((x + bw) * s + m, w),
                        min((y + bh) * s + m, h)))
            cells.append(cv2.countNonZero(fg[y:y + bh, x:x + bw]))
        return stacked_joined(out, cells)

    def foreground_low(self, masks: list[tuple[Box, NDArray[np.bool_]]]) -> U8 | None:
        """The verified objects' masks (box, mask over it) at the floor's low resolution (the stride's grid
        points), for `update_floor`; None without any."""
        if not masks:
            return None
        s = self.cfg.stride
        low = np.zeros(self.low_shape, np.uint8)
        for (x0, y0, _, _), mask in masks:
            sub = mask[(-y0) % s::s, (-x0) % s::s]
            ly, lx = (y0 + s - 1) // s, (x0 + s - 1) // s
            low[ly:ly + sub.shape[0], lx:lx + sub.shape[1]] |= sub.astype(np.uint8)
        return low

    def update_floor(self, foreground_low: U8 | None) -> None:
        """Let the floor rise by one grey level where the residual is above it: every frame for
        background pixels, every `_fg_every` frames under verified objects. Frozen while moving."""
        self._objects_low = None if foreground_low is None else foreground_low * np.uint8(255)
        if self._pending is None:
            return
        resid, moving = self._pending
        self._count += 1
        if moving:
            return
        up = cv2.compare(resid, self.floor, cv2.CMP_GT)
        if foreground_low is not None and self._count % self._fg_every:
            up[foreground_low > 0] = 0
        cv2.add(self.floor, self._ones, dst=self.floor, mask=up)
