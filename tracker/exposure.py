"""The reference camera's exposure matched to the key camera's before eq. (9) (issue 12: real cameras).

Eq. (9) compares the key (left) camera's grey Γ(x, y) with the reference (right) camera's Θ(x', y') at the
learnt background's correspondence. It is lighting-independent because a change of the scene's light
changes both images alike. Two real cameras do not stay alike: each has its own auto-exposure, gain and
sensor, so the ratio of their greys steps or drifts whenever one of them re-exposes, and every background
pixel then differs by that share of its grey (20 % of a mid-grey scene is 20 to 40 grey levels, past eq.
(9)'s ε everywhere). With the cameras still, the temporal model of the left image draws the outlines and
does not see it; while they move, eq. (9) stands alone. Measured on pan:body (2026-12-02) with the right
camera's exposure stepped to 0.8 or 1.2 times the left's at 2 s: detection 1.00 -> 0.25 and 38 or 6
false-target frames, without this stage.

An exposure scales the light each pixel gathers, and the camera's tone curve (a power law, its gamma)
keeps a ratio a ratio, so one factor k relates the two images' greys over a background seen alike:
Γ(x, y) ≈ k Θ(x', y'). Per frame, k is the median of Γ / Θ over the candidate grid's samples at the learnt
background's correspondence (those eq. (9) compares), leaving out dark and saturated samples (under `lo`
or over `hi` grey levels) and those on or about the objects found in the last frame (tracker.detect), and
the reference image is scaled by k before the frame's stages read it; the survey's pairs are learnt again
so matched where they differ (tracker.pipeline.learn_background), or eq. (9)'s floors would hold the
difference. Within `dead_band` of 1 the image is left as it is: the scale would round each grey by a level
or two, which ε absorbs, and images alike stay untouched. A median holds while most samples are
background seen alike: an object new in the frame that covers a third of the view, shaded from one side
to the other, moved it by about 3 % in a test with sensor noise (2026-12-02, before the last frame's
objects were left out).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

U8 = NDArray[np.uint8]


@dataclass(frozen=True)
class ExposureConfig:
    """dead_band: |k - 1| at or under which the reference image is left as it is; min_samples: with fewer
    usable samples than this the last ratio measured stands (1 before any); lo, hi: the usable samples'
    greys in both images."""

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
        if n < c.min_samples:  # too few to tell (a view mostly covered): the last measured ratio stands
            self.last = ExposureRatio(self.last.k, n, self.last.applied)
            return self.last
        k = float(np.median(key[use].astype(np.float32) / ref[use].astype(np.float32)))
        self.last = ExposureRatio(k, n, abs(k - 1.0) > c.dead_band)
        return self.last

    def guessed(self, left: U8, right: U8) -> ExposureRatio:
        """k from two whole images (H, W) alone, before any correspondence is known (a survey's first
        pair): the ratio of their mean greys, the two cameras seeing much the same scene (within 0.3 % of
        1 on the simulator's alike cameras at every survey pose of walk, pan, occlusion, foliage and
        approach). Does not count as the last measurement."""
        a, b = float(np.mean(left)), float(np.mean(right))
        if min(a, b) < self.cfg.lo:  # a dark view tells nothing
            return ExposureRatio(1.0, left.size, False)
        return ExposureRatio(a / b, left.size, abs(a / b - 1.0) > self.cfg.dead_band)

    @staticmethod
    def balanced(right: U8, ratio: ExposureRatio) -> U8:
        """The right image (H, W) uint8 scaled by k where the ratio says so (rounded, saturated at 255);
        the same array otherwise."""
        if not ratio.applied:
            return right
        return np.asarray(cv2.convertScaleAbs(right, alpha=ratio.k), np.uint8)
