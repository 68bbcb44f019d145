"""Temporal candidates: objects that stand too close to their background for the stereo residual.

An object a few per cent of its range in front of its background (a person 0.2 m before a wall at 7 m:
0.8 px of disparity at f·b = 180 px·m) leaves almost no residual in eq. (9), whose warp is off by that
disparity only, and fails the stereo verifier's depth-gap test. With the cameras still, the left image's
temporal model (background B and mean deviation D per pixel, at gain 1; tracker.detect) sees it at once:

1. Candidates, on the stride grid: |Γ - g B| beyond the local range of g B (its min and max over a 3x3
   cell neighbourhood, so a texture that sways or jitters by a few pixels stays in) by more than
   ε + 3 g D; g is the frame's global gain, the median of Γ / B over the grid (a light step scales Γ, not
   the model); rows whose D has not been learnt yet raise nothing. Groups of cells touching objects the
   stereo stages found stand clear of their background are left to them; an object verified here that
   is larger than those near their background it touches replaces them (the stereo residual of an
   object near its background shows only parts of it).
2. Verification of each group at full resolution: the outline from the temporal model at the ring gain
   (tracker.masks.temporal_outline); a region whose texture is the background's own relit (zero-mean
   normalised correlation of Γ with B over it above `max_texture_corr`: a shadow, a local change of
   light) is dropped; the range comes from matching the region itself between the two cameras
   (tracker.stereo through the verifier's strips) and must not lie behind the known background by more
   than `behind_tolerance_px` (a background uncovered where the learnt geometry held an object lies
   behind it); a region matched clear of its background must show in the right camera's eq. (9) at that
   disparity too (a small region searched over the whole range may match a look-alike far off: a head of
   95 px at 27 m matched at 153 px, 1.2 m); of a region that also holds something at another depth, the
   part that is one surface at the matched disparity is kept (and matched again).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.boxes import stacked_joined
from tracker.detect import Box, StereoSubtractor
from tracker.frames import StereoFrame
from tracker.growth import can_grow, grow_tracked
from tracker.masks import frame_gain, largest_region, temporal_outline, with_parts
from tracker.one_camera import OneCameraConfig, coast_sigma_px, hidden_from_right, nearest_prediction
from tracker.rectify import Rectifier
from tracker.regions import background_disparity, mask_centroid, median_behind, nearest_hint
from tracker.results import Blob
from tracker.stereo import RegionMatch
from tracker.verify import Verifier

F32 = NDArray[np.float32]
F64 = NDArray[np.float64]
U8 = NDArray[np.uint8]
BoolA = NDArray[np.bool_]
_NB = np.ones((3, 3), np.uint8)


@dataclass(frozen=True)
class TemporalConfig:
    """min_area_px: smallest region (full-resolution pixels); max_texture_corr: ZNCC of Γ with B over a
    region above which it is the background relit; behind_tolerance_px: how far behind the background
    (disparity, px; the background's is the median over the region) a region may match; learnt_updates:
    updates of the background's deviation D a row needs before it raises candidates (each row is updated
    every 24 frames); right_seen_share: of a region matched clear of its background (beyond twice the
    stereo depth test), the share the right camera's eq. (9) mask must cover at the matched disparity."""

    min_area_px: int = 64
    max_texture_corr: float = 0.6
    behind_tolerance_px: float = 0.15
    learnt_updates: int = 3
    right_seen_share: float = 0.5

    def __post_init__(self) -> None:
        if not 0.0 <= self.right_seen_share <= 1.0:
            raise ValueError(f"right_seen_share must be in 0..1, got {self.right_seen_share}")


def change_mask(key: U8, bg: F32, dev: F32, g: float, eps: int) -> U8:
    """Cells (0/255) where Γ lies outside [g min₃ₓ₃ B, g max₃ₓ₃ B] by more than ε + 3 g max₃ₓ₃ D."""
    hi = np.asarray(cv2.dilate(bg, _NB), np.float32)
    lo = np.asarray(cv2.erode(bg, _NB), np.float32)
    lim = np.float32(eps) + np.float32(3.0 * g) * np.asarray(cv2.dilate(dev, _NB), np.float32)
    k = key.astype(np.float32)
    gf = np.float32(g)
    out = (k > gf * hi + lim) | (k < gf * lo - lim)
    return out.astype(np.uint8) * np.uint8(255)


def texture_corr(key: U8, bg: F32, mask: NDArray[np.bool_]) -> float:
    """Zero-mean normalised correlation of Γ and B over the mask's pixels (1: the same texture)."""
    a = key[mask].astype(np.float64)
    b = bg[mask].astype(np.float64)
    a -= a.mean()
    b -= b.mean()
    den = float(np.sqrt((a @ a) * (b @ b)))
    return float(a @ b) / den if den > 1e-9 else 1.0


_WIN = (5, 5)


def _same_surface(rect: Rectifier, frame: StereoFrame, box: Box, obj: NDArray[np.bool_], d: float, eps: int
                  ) -> NDArray[np.bool_]:
    """The part of a changed region that is one surface at disparity d: pixels whose 5x5 mean of
    |Γ(x, y) - Θ(x_r, y_r)| is at most 2ε, (x_r, y_r) the raw right pixel of the rectified left point
    shifted by d; its largest component, grown back by two pixels inside the region. What the region
    also holds at another depth (a background uncovered next to the object) drops out."""
    x0, y0, x1, y1 = box
    theta = rect.right_image_at(frame.right, box, d)
    diff = cv2.blur(cv2.absdiff(frame.left[y0:y1, x0:x1], theta).astype(np.float32), _WIN)
    same = largest_region(obj & (diff <= 2 * eps))
    return np.asarray(cv2.dilate(same.view(np.uint8), _NB, iterations=2) > 0) & obj


def _overlap(a: Box, b: Box) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def _shared(a: Blob, b: Blob) -> int:
    """How many pixels the masks of two blobs share (raw left image)."""
    x0, y0, x1, y1 = max(a.box[0], b.box[0]), max(a.box[1], b.box[1]), min(a.box[2], b.box[2]), min(a.box[3], b.box[3])
    if x0 >= x1 or y0 >= y1:
        return 0
    ma = a.mask[y0 - a.box[1]:y1 - a.box[1], x0 - a.box[0]:x1 - a.box[0]]
    mb = b.mask[y0 - b.box[1]:y1 - b.box[1], x0 - b.box[0]:x1 - b.box[0]]
    return int(np.count_nonzero(ma & mb))


def without_duplicates(blobs: list[Blob]) -> list[Blob]:
    """The blobs less those with more than half of their pixels inside the mask of a larger one: one
    object verified again from an overlapping candidate box (two objects do not share pixels)."""
    kept: list[Blob] = []
    for b in sorted(blobs, key=lambda b: -b.area):
        if not any(2 * _shared(b, k) > b.area for k in kept):
            kept.append(b)
    return [b for b in blobs if any(b is k for k in kept)]


def _union_area(blobs: list[Blob]) -> int:
    """The number of pixels in the union of the blobs' masks."""
    x0, y0 = min(b.box[0] for b in blobs), min(b.box[1] for b in blobs)
    x1, y1 = max(b.box[2] for b in blobs), max(b.box[3] for b in blobs)
    canvas = np.zeros((y1 - y0, x1 - x0), bool)
    for b in blobs:
        canvas[b.box[1] - y0:b.box[3] - y0, b.box[0] - x0:b.box[2] - x0] |= b.mask
    return int(np.count_nonzero(canvas))


def _without_rims(blobs: list[Blob]) -> list[Blob]:
    """The blobs less those under a tenth of the area of a blob whose box overlaps theirs: the rim left
    around an object (the verifier's rule for a second object in one box, applied to the outlines). Not a
    piece at the image's left border verified at a track's disparity (Blob.part_only), which the pipeline
    joins to that track's object or drops: the end of a car left of a post, under a tenth of the car once
    the post hides the rest of it (occlusion:body, frames 185-214)."""
    return [b for b in blobs if b.part_only or not any(
        o is not b and _overlap(o.box, b.box) and b.area < o.area // 10 for o in blobs)]


def _unclaimed(coasting: Callable[[], F64], blobs: list[Blob], gate_px: float) -> F64:
    """The rows of `coasting()` (MultiTracker.coasting) whose predicted position no object found already
    holds in its box, nor lies within `gate_px` of a one-camera object's centroid (it continued that track):
    one object per track. A part only (Blob.part_only) claims none: the pipeline keeps it only if it joins."""
    coast = coasting()
    blobs = [b for b in blobs if not b.part_only]
    if not blobs:
        return coast
    keep = [not any(b.box[0] <= c[0] < b.box[2] and b.box[1] <= c[1] < b.box[3]
                    or b.one_camera and float(np.hypot(*(c[:2] - b.centroid_raw))) <= gate_px for b in blobs)
            for c in coast]
    return np.asarray(coast[np.array(keep, bool)], np.float64)


class TemporalDetector:
    """Candidates and verification from the left temporal model while the cameras are still.
    `detect(frame, found, hints)` -> all the frame's blobs; `gain` is the last frame's global gain (or None)."""

    def __init__(self, sub: StereoSubtractor, verifier: Verifier, config: TemporalConfig | None = None,
                 one_camera: OneCameraConfig | None = None):
        self.sub, self.verifier = sub, verifier
        self.cfg = config or TemporalConfig()
        self.one_cfg = one_camera or OneCameraConfig()
        self.gain: float | None = None

    def detect(self, frame: StereoFrame, found: list[Blob], hints: F64 | None,
               coast: Callable[[], F64] | None = None) -> list[Blob]:
        """All the frame's objects: those the stereo stages `found`, those of them near their background
        replaced by the temporal model's object over the changed region they lie in when that is larger,
        and the changed regions they do not touch verified as new objects, or as tracked objects the right
        camera cannot see (coast: gives MultiTracker.coasting at this frame's pose, asked for only where a
        region matches nowhere; None: none such)."""
        self.gain = None
        model = self.sub.left_background(frame.gimbal)
        if model is None:
            return found
        s, eps = self.sub.cfg.stride, self.sub.cfg.epsilon
        bg, dev = model
        key, bl = frame.left[::s, ::s], bg[::s, ::s]
        g = frame_gain(frame.left, bg, s)
        if g is None:
            return found
        self.gain = g
        fg = change_mask(key, np.ascontiguousarray(bl), np.ascontiguousarray(dev[::s, ::s]), g, eps)
        learnt = self.sub.learnt_rows(frame.gimbal, self.cfg.learnt_updates)
        if learnt is not None:
            fg[~learnt[::s]] = 0  # no deviation known there yet
        out = list(found)
        for box in self._groups(fg):
            covered = [b for b in out if _overlap(b.box, box) and not b.part_only]  # a part only may not join
            if covered and not all(self._near_background(b) for b in covered):
                continue  # objects well clear of their background: their stereo outline holds
            claims = None if coast is None else partial(_unclaimed, coast, out, self.one_cfg.gate_px)
            blob = self.verify(frame, box, bg, dev, g, hints, claims)
            if blob is None or (covered and blob.area <= _union_area(covered)):
                continue
            out = [b for b in out if all(b is not c for c in covered)] + [blob]
        return _without_rims(out)

    def _near_background(self, b: Blob) -> bool:
        """Whether a stereo object is within twice the depth-gap test of its background: its residual then
        shows only parts of it, and the temporal model's outline may hold more."""
        return self._near(b.disparity, b.bg_disparity)

    def _near(self, d: float, d_bg: float) -> bool:
        """Whether disparity d (px) is within twice the depth-gap test of the background's d_bg."""
        cfg = self.sub.cfg
        return d < d_bg * (1.0 + 2.0 * cfg.min_depth_gap) + 2.0 * cfg.min_disparity_gap_px

    def _right_sees(self, frame: StereoFrame, box: Box, obj: BoolA, d: float) -> bool:
        """Whether the right camera's eq. (9) mask, sampled at disparity d, covers at least
        `right_seen_share` of the region (an object clear of its background shows in both keys)."""
        seen = self.verifier.right_key_at(frame, box, d)
        return int(np.count_nonzero(seen & obj)) >= self.cfg.right_seen_share * int(np.count_nonzero(obj))

    def _groups(self, fg: U8) -> list[Box]:
        """Boxes (raw pixels, with the detector's margin) around groups of changed cells large enough, those
        one above the other joined (boxes.stacked_joined, as eq. (9)'s are): a walker the left camera alone
        sees at the left border, its change split at the waist (endless:body, frames 487-488: its legs
        alone, 30-32 px from the truth's centroid, against 3.4 and 1.4 px joined)."""
        if cv2.countNonZero(fg) == 0:
            return []
        s, m = self.sub.cfg.stride, self.sub.cfg.margin_px
        w, h = self.sub.bg.rect.rig.left.size
        n, labels, stats, _ = cv2.connectedComponentsWithStats(cv2.dilate(fg, _NB), connectivity=8)
        min_cells = max(2, self.cfg.min_area_px // (s * s))
        out, cells = [], []
        for i in range(1, n):
            x, y, bw, bh, _area = (int(v) for v in stats[i])
            k = cv2.countNonZero((labels[y:y + bh, x:x + bw] == i).view(np.uint8) & fg[y:y + bh, x:x + bw])
            if k < min_cells:
                continue
            out.append((max(x * s - m, 0), max(y * s - m, 0), min((x + bw) * s + m, w), min((y + bh) * s + m, h)))
            cells.append(k)
        return list(stacked_joined(out, cells)[0])

    def verify(self, frame: StereoFrame, box: Box, bg: F32, dev: F32, g: float, hints: F64 | None,
               coast: Callable[[], F64] | None = None) -> Blob | None:
        """One changed region: its outline, the relit-texture test, its own disparity and the test that it
        does not lie behind the background; failing these, a tracked object the right camera cannot see
        (coast: gives MultiTracker.coasting at this frame's pose; None: no such sightings; tracker.one_camera). A
        match refused as behind the background is no evidence against it there: the sliver of a walker beside
        a post holds pixels whose learnt background is the post (endless:body, frames 2306-2314: refused so,
        they were lost again)."""
        cfg, eps = self.cfg, self.sub.cfg.epsilon
        x0, y0, x1, y1 = box
        key, b, d = frame.left[y0:y1, x0:x1], bg[y0:y1, x0:x1], dev[y0:y1, x0:x1]
        region = change_mask(key, b, d, g, eps) > 0
        obj, gain, changed = temporal_outline(key, b, d, np.zeros_like(region), region, eps)
        if int(np.count_nonzero(obj)) < cfg.min_area_px:
            return None
        if texture_corr(key, b, obj) > cfg.max_texture_corr:
            return None  # the background's own texture, relit: a shadow or a local change of light
        hint = nearest_hint(hints, obj, box)
        radius = self.verifier.search_radius(hint)  # about a track's prediction: how far it can move
        fine = self._match(frame, box, obj, hint, radius, hint is not None)
        blob = None if fine is None else self._checked(frame, box, obj, gain, fine, hint, radius)
        if blob is not None and hint is not None:
            blob = self._grown(frame, box, blob, (bg, dev), changed)
        if blob is None and coast is not None:  # the left camera alone: every part of the body it sees
            return self._left_only(frame, box, with_parts(obj, region), gain, coast())
        return blob

    def _match(self, frame: StereoFrame, box: Box, obj: BoolA, d0: float | None, radius: int, tracked: bool
               ) -> RegionMatch | None:
        """RegionMatcher.match_object on the region's pixels the right camera sees at d0 (its seen_by_right;
        all of them without a d0, or where that match fails), as the stereo stage matches a tracked object: a
        board beside a nearer box the right camera sees in front of its right side (endless:plate, frames
        240-251), matched with those columns too, was 1.4 px too near (0.5 m at 7.7 m) against 0.1 px."""
        seen = None if d0 is None else self.verifier.seen_by_right(frame, box, obj, d0)
        return self.verifier.match_part_or_whole(frame, box, seen, obj, d0, radius, tracked)

    def _checked(self, frame: StereoFrame, box: Box, obj: BoolA, gain: float, fine: RegionMatch, hint: float | None,
                 radius: int) -> Blob | None:
        """A region's object from its stereo match `fine`: the part that is one surface at it (matched again
        where that is less than 9/10 of the region), not behind the background, seen by both cameras."""
        cfg, eps = self.cfg, self.sub.cfg.epsilon
        same = _same_surface(self.verifier.rect, frame, box, obj, fine.disparity, eps)
        if int(np.count_nonzero(same)) < cfg.min_area_px:
            return None
        if int(np.count_nonzero(same)) < 0.9 * int(np.count_nonzero(obj)):  # part of it was something else
            obj = same
            again = self._match(frame, box, obj, fine.disparity, radius, hint is not None)
            if again is None:
                return None
            fine = again
        cm = self.sub.correspondence(0, frame.gimbal, box)
        d_bg = background_disparity(cm, obj, mask_centroid(obj.view(np.uint8))[1])
        d_med = median_behind(cm, obj, d_bg)
        if fine.disparity < d_med - max(cfg.behind_tolerance_px, 3.0 * fine.sigma):
            return None  # behind the known background: background uncovered, not an object
        # clear of the background (the median the test above takes), yet the right camera sees nothing
        # there: a false match
        if not self._near(fine.disparity, d_med) and not self._right_sees(frame, box, obj, fine.disparity):
            return None
        return self._blob(box, obj, fine.disparity, fine.sigma, d_bg, fine.score, gain, False)

    def _grown(self, frame: StereoFrame, box: Box, b: Blob, model: tuple[F32, F32], changed: BoolA) -> Blob:
        """A tracked object's outline grown into the box's `changed` pixels that are its surface too
        (growth.grow_tracked, as tracker.verify grows a tracked object's stereo outline; the temporal outline
        keeps its largest region alone): where eq. (9) sees little of a walker before a low wall at its own
        depth, the parts of its legs the model saw apart from the rest."""
        if not can_grow(b.mask, changed, self.cfg.min_area_px):
            return b
        cm = self.sub.correspondence(0, frame.gimbal, box)
        at = self.verifier.at_depth(frame, box, cm, model, b.disparity)
        obj = grow_tracked(self.verifier.rect, frame, box, cm, model[0], b.mask, changed, b.disparity,
                           self.sub.cfg.epsilon, self.cfg.min_area_px, at)
        if int(np.count_nonzero(obj)) == b.area:
            return b
        return self._blob(box, obj, b.disparity, b.disparity_sigma, b.bg_disparity, b.score, b.gain, b.one_camera)

    def _left_only(self, frame: StereoFrame, box: Box, obj: BoolA, gain: float, coast: F64) -> Blob | None:
        """A region that matches at no disparity as a tracked object seen by the left camera alone: of the
        tracks whose last stereo sighting is at most `max_frames` updates old (rows of `coast`), the one whose
        predicted position lies nearest its centroid, within the association gate, and the right camera
        cannot see at least `min_hidden` of the region at that track's held disparity
        (tracker.one_camera.hidden_from_right). Its disparity is the held one."""
        rect, cfg = self.verifier.rect, self.one_cfg
        coast = coast[coast[:, 3] < cfg.max_frames]
        c_box = mask_centroid(obj.view(np.uint8))[1]
        k = nearest_prediction(coast, c_box + box[:2], cfg)
        if k is None:
            return None
        d = float(coast[k, 2])
        ext = (box[0], box[1], min(box[2] + self.sub.bg.num_disparities, rect.rig.left.size[0]), box[3])
        cm = self.sub.correspondence(0, frame.gimbal, ext)
        hidden = hidden_from_right(rect, box, obj, d, cm, ext, cfg)
        if int(np.count_nonzero(hidden)) < cfg.min_hidden * int(np.count_nonzero(obj)):
            return None
        sigma = coast_sigma_px(d, float(coast[k, 4]), float(coast[k, 5]), rect.f * rect.b, cfg)
        d_bg = background_disparity(cm.crop((0, 0, box[2] - box[0], box[3] - box[1])), obj, c_box)
        return self._blob(box, obj, d, sigma, d_bg, 0.0, gain, True)

    def _blob(self, box: Box, obj: BoolA, d: float, sigma: float, d_bg: float, score: float, gain: float,
              one_camera: bool) -> Blob:
        """The Blob of a region: its area, eq. (10) in raw pixels and, weighting each pixel by its area, in
        rectified ones (Σ a x / Σ a, Σ a y / Σ a)."""
        x0, y0, x1, y1 = box
        m8 = obj.view(np.uint8)
        area, c_box = mask_centroid(m8)
        sx, sy, sa, _ = cv2.mean(self.verifier.rect.area_moments[y0:y1, x0:x1], mask=m8)
        return Blob(box, obj, area, c_box + (x0, y0), np.array([sx / sa, sy / sa]), d, sigma, d_bg, score, gain,
                    one_camera)
