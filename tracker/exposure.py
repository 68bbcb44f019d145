"""The reference camera's exposure matched to the key camera's before eq. (9) (issue 12: real cameras).

Eq. (9) compares the key (left) camera's grey Γ(x, y) with the reference (right) camera's Θ(x', y') at the
learnt background's correspondence. It is lighting-independent because a change of the scene's light
changes both images alike. Two real cameras do not stay alike: each has its own auto-exposure, gain and
sensor, so the ratio of their greys steps or drifts whenever one of them re-exposes, and every background
pixel then differs by that share of its grey (20 % of a mid-grey scene is 20 to 40 grey levels, past eq.
(9)'s ε everywhere). With the cameras still, the temporal model of the left image draws the outlines and
does not see it; while they move, eq. (9) stands alone. Measured on pan:body (2026-12-02) with the right
camera's exposure stepped by +20 % or -20 % at 2 s: detection 1.00 -> 0.25 and 28 or 37 false-target
frames, without this stage.

An exposure scales the light each pixel gathers, and the camera's tone curve (a power law, its gamma)
keeps a ratio a ratio, so one factor k relates the two images' greys over a background seen alike:
Γ(x, y) ≈ k Θ(x', y'). Per frame, k is the median of Γ / Θ over the candidate grid's samples at the learnt
background's correspondence (those eq. (9) compares; most of them are background, and a median ignores
the rest), leaving out dark and saturated samples (under `lo` or over `hi` grey levels), and the
reference image is scaled by k before any stage reads it. Within `dead_band` of 1 it is left as it is:
the scale would round each grey by a level or two, which ε absorbs, and images alike stay untouched.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

U8 = NDArray[np.uint8]


@dataclass(frozen=True)
class ExposureConfig:
    """dead_band: |k - 1| at or under which the reference image is left as it is; min_samples: fewer usable
    samples than this measure nothing (k = 1); lo, hi: the usable samples' greys in both images."""

    dead_band: float = 0.03
    min_samples: int = 500
    lo: int = 16
    hi: int = 239

    def __post_init__(self) -> None:
        if not self.dead_band >= 0.0:
            raise ValueError(f"dead_band must be at least 0, got {self.dead_band}")
        if not 0 <= self.lo < self.hi <= 255:
            raise ValueError(f"lo and hi must be greys with 0 <= lo < hi <= 255, got {self.lo} and {self.hi}")


@dataclass(frozen=True)
class ExposureRatio:
    """One frame's measurement: k = Γ / Θ over the background (the median), the samples it was taken over,
    and whether the reference image was scaled by it."""

    k: float
    samples: int
    applied: bool


class ExposureBalance:
    """`step(key, ref, valid)` -> ExposureRatio; `balanced(right, ratio)` -> the right image scaled by k."""

    def __init__(self, config: ExposureConfig | None = None):
        self.cfg = config or ExposureConfig()
        self.last = ExposureRatio(1.0, 0, False)

    def step(self, key: U8, ref: U8, valid: U8) -> ExposureRatio:
        """k from the key image's samples `key` (h, w) and the reference image's at the background's
        correspondence `ref` (h, w), where `valid` (h, w) is nonzero."""
        c = self.cfg
        use = (valid > 0) & (key >= c.lo) & (key <= c.hi) & (ref >= c.lo) & (ref <= c.hi)
        n = int(np.count_nonzero(use))
        if n < c.min_samples:
            self.last = ExposureRatio(1.0, n, False)
            return self.last
        k = float(np.median(key[use].astype(np.float32) / ref[use].astype(np.float32)))
        self.last = ExposureRatio(k, n, abs(k - 1.0) > c.dead_band)
        return self.last

    @staticmethod
    def balanced(right: U8, ratio: ExposureRatio) -> U8:
        """The right image (H, W) uint8 scaled by k where the ratio says so (rounded, saturated at 255);
        the same array otherwise."""
        if not ratio.applied:
            return right
        return np.asarray(cv2.convertScaleAbs(right, alpha=ratio.k), np.uint8)
