"""Learning the background from a stream with moving objects in it: no empty scene needed.

A real source starts from its first pair as the background (the tracker runs from frame 0), while a
StreamLearner keeps samples of the stream taken while the cameras are still at the learnt pose: every
`sample_every`-th pair, divided by the frame's global gain g (tracker.masks.global_gain) so that a
change of light does not enter the statistics, with the pixels of the objects the tracker found marked
(in the right image at the object's disparity; both grown by a few pixels). Each relearn takes the
per-pixel median of the last `window` samples of each camera over the samples where the pixel was not an
object's (the background in use where it always was),

    B(x, y) = median_i Γ_i(x, y) / g_i,        D(x, y) = mean_i |Γ_i(x, y) / g_i - B(x, y)|,

a pair without the objects that moved (each pixel is background in most samples) nor those tracked. The
pipeline then learns the background's geometry again from that pair (tracker.bgdepth by semi-global
matching), so a place where an object stood at start-up gets the geometry and texture of what is behind
it once the object has walked away. Relearns come after `first_after` samples, then at periods doubling
up to `max_every` samples: the background is kept up to date while the mount is still.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.frames import GimbalState, StereoFrame

U8 = NDArray[np.uint8]
F32 = NDArray[np.float32]
Box = tuple[int, int, int, int]
_GROW = np.ones((5, 5), np.uint8)


@dataclass(frozen=True)
class StreamLearnConfig:
    """sample_every: frames between samples; window: samples in the median; first_after: samples before
    the first relearn; max_every: the longest period between relearns (samples); bands: frames a relearn's
    statistics are spread over (a band of rows each)."""

    sample_every: int = 4
    window: int = 31
    first_after: int = 8
    max_every: int = 240
    bands: int = 16

    def __post_init__(self) -> None:
        if min(self.sample_every, self.window, self.first_after, self.max_every) < 1 or self.window > 255:
            raise ValueError("sample_every, first_after and max_every must be >= 1, window in 1..255")


@dataclass(frozen=True)
class LearntBackground:
    """A background pair at gain 1: per-pixel medians of the samples (H, W) uint8 each, the left's mean
    absolute deviation from its median (H, W) float32 (grey levels), and how many samples it comes from."""

    left: U8
    right: U8
    left_dev: F32
    samples: int


@dataclass(frozen=True)
class Sighting:
    """An object the tracker found in a frame: its left box (x0, y0, x1, y1), bool mask and disparity (px)."""

    box: Box
    mask: NDArray[np.bool_]
    disparity: float


def median_u8(stack: list[U8], valid: list[NDArray[np.bool_]], fallback: U8) -> U8:
    """The per-pixel lower median of the valid samples of uint8 images (n <= 255), found bit by bit from
    the top: the k-th smallest valid value (k = (n_valid - 1) // 2) is at least c exactly when at most k
    valid samples lie below c. `fallback` where no sample is valid."""
    nv = np.zeros(stack[0].shape, np.int16)
    for v in valid:
        nv += v
    k = (nv - 1) // 2
    res = np.zeros_like(stack[0])
    cnt = np.empty(stack[0].shape, np.int16)
    for bit in range(7, -1, -1):
        cand = res | np.uint8(1 << bit)
        cnt[:] = 0
        for s, v in zip(stack, valid, strict=True):
            cnt += (s < cand) & v  # valid samples below the candidate
        np.copyto(res, cand, where=cnt <= k)
    np.copyto(res, fallback, where=nv == 0)
    return res


@dataclass(frozen=True)
class _Sample:
    """One sample at gain 1, with the pixels not covered by objects (True) in each image."""

    left: U8
    right: U8
    valid_left: NDArray[np.bool_]
    valid_right: NDArray[np.bool_]


def _robust_pair(samples: list[_Sample], ref: tuple[U8, U8], bands: int) -> Iterator[LearntBackground | None]:
    """The medians and the left's mean absolute deviation of the samples, a band of rows per step (None
    until the last): spread over `bands` frames, no frame pays for the whole image."""
    h = ref[0].shape[0]
    left, right = np.empty_like(ref[0]), np.empty_like(ref[1])
    dev = np.zeros(ref[0].shape, np.float32)
    for i in range(bands):
        r = slice(i * h // bands, (i + 1) * h // bands)
        left[r] = median_u8([s.left[r] for s in samples], [s.valid_left[r] for s in samples], ref[0][r])
        right[r] = median_u8([s.right[r] for s in samples], [s.valid_right[r] for s in samples], ref[1][r])
        med, n = left[r].astype(np.float32), np.zeros(dev[r].shape, np.float32)
        for s in samples:
            dev[r] += np.where(s.valid_left[r], np.abs(s.left[r].astype(np.float32) - med), np.float32(0.0))
            n += s.valid_left[r]
        dev[r] /= np.maximum(n, np.float32(1.0))
        yield None
    yield LearntBackground(left, right, dev, len(samples))


class StreamLearner:
    """Collects samples while the cameras are still at `pose` and returns a LearntBackground when a relearn
    is complete (its statistics are spread over `bands` frames). `observe(frame, gain, still, seen)`;
    `reference(left, right)` sets the background pair in use."""

    def __init__(self, first: StereoFrame, config: StreamLearnConfig | None = None):
        self.cfg = config or StreamLearnConfig()
        self.pose = _pose(first.gimbal)
        self._ref = (first.left.copy(), first.right.copy())
        self._samples: deque[_Sample] = deque(maxlen=self.cfg.window)
        self._job: Iterator[LearntBackground | None] | None = None
        self._frames = 0
        self._since = 0
        self._every = self.cfg.first_after
        self.relearns = 0

    @property
    def reference_left(self) -> U8:
        """The left image of the background pair in use (gain 1)."""
        return self._ref[0]

    def reference(self, left: U8, right: U8) -> None:
        """The background pair now in use (gain 1): it stands where a pixel was an object's in every sample."""
        self._ref = (left, right)

    def observe(self, frame: StereoFrame, gain: float, still: bool, seen: list[Sighting]) -> LearntBackground | None:
        """Take a sample if one is due (cameras still at the pose, gain known), advance a relearn under
        way by a band of rows, and return the LearntBackground when one is complete."""
        if not still or _pose(frame.gimbal) != self.pose:
            self._samples.clear()
            self._since, self._job = 0, None
            return None
        if self._job is not None:
            done = next(self._job)
            if done is not None:
                self._job = None
                self.relearns += 1
            return done
        self._frames += 1
        if self._frames % self.cfg.sample_every or not gain > 0:
            return None
        inv = 1.0 / gain
        left = np.asarray(cv2.convertScaleAbs(frame.left, alpha=inv), np.uint8)
        right = np.asarray(cv2.convertScaleAbs(frame.right, alpha=inv), np.uint8)
        m_left, m_right = _object_masks(seen, left.shape)
        self._samples.append(_Sample(left, right, ~m_left, ~m_right))
        self._since += 1
        if self._since >= self._every:
            self._since = 0
            self._every = min(2 * self._every, self.cfg.max_every)
            self._job = _robust_pair(list(self._samples), self._ref, self.cfg.bands)
        return None


def changed_box(before: U8, after: U8, eps: int, min_area: int, grow: int = 12) -> Box | None:
    """The bounding box (x0, y0, x1, y1), grown by `grow` pixels, of the pixels where two background
    images differ by more than 2ε after an opening (noise and single pixels out); None below min_area."""
    diff = ((cv2.absdiff(before, after) > 2 * eps).astype(np.uint8))
    diff = np.asarray(cv2.morphologyEx(diff, cv2.MORPH_OPEN, np.ones((3, 3), np.uint8)), np.uint8)
    if cv2.countNonZero(diff) < min_area:
        return None
    x, y, w, h = cv2.boundingRect(diff)
    H, W = diff.shape
    return (max(x - grow, 0), max(y - grow, 0), min(x + w + grow, W), min(y + h + grow, H))


def _object_masks(seen: list[Sighting], shape: tuple[int, ...]) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    """The objects' pixels in the left image, and in the right image about where the right camera sees
    them (shifted left by their disparity), both grown by two pixels."""
    h, w = shape[0], shape[1]
    m_left = np.zeros((h, w), np.uint8)
    m_right = np.zeros((h, w), np.uint8)
    if not seen:
        return m_left > 0, m_right > 0
    for s in seen:
        x0, y0, x1, y1 = s.box
        m_left[y0:y1, x0:x1] |= s.mask.view(np.uint8)
        shift = np.array([[1.0, 0.0, x0 - s.disparity], [0.0, 1.0, float(y0)]], np.float32)
        m_right |= np.asarray(cv2.warpAffine(s.mask.view(np.uint8), shift, (w, h), flags=cv2.INTER_NEAREST), np.uint8)
    return (np.asarray(cv2.dilate(m_left, _GROW) > 0), np.asarray(cv2.dilate(m_right, _GROW) > 0))


def _pose(gimbal: GimbalState | None) -> tuple[float, float]:
    g = gimbal or GimbalState()
    return (round(g.pan_deg, 4), round(g.tilt_deg, 4))
