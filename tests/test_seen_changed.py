"""The pixels an object's disparity is matched on (tracker.masks.seen_changed): not the background that shows
through the gaps its filled outline encloses."""

from __future__ import annotations

import cv2
import numpy as np

from tracker.masks import seen_changed
from tracker.stereo import refine_region

H, W, X0 = 80, 160, 80


def _texture(rng: np.random.Generator, sigma: float, lo: float, hi: float) -> np.ndarray:
    t = cv2.GaussianBlur(rng.standard_normal((H, W + 40)).astype(np.float32), (0, 0), sigma)
    t = (t - t.min()) / (t.max() - t.min())
    return lo + t * (hi - lo)


def _walker_before_hedge() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A rectified pair: a smooth, low-contrast figure (a torso over two legs 6 px apart) at disparity 10 px
    before a sharp, high-contrast background at 6 px, and the figure's own pixels."""
    rng = np.random.default_rng(3)
    bg, body = _texture(rng, 1.0, 40, 220), _texture(rng, 3.0, 110, 150)
    own = np.zeros((H, W), bool)
    own[10:30, X0:X0 + 26] = True
    own[30:70, X0:X0 + 10] = True
    own[30:70, X0 + 16:X0 + 26] = True
    left = np.where(own, body[:, :W], bg[:, :W])
    xs = np.arange(W)
    right = np.empty_like(left)
    for y in range(H):  # right x sees the figure where x + 10 lies on it, else the background at x + 6
        on = own[y, np.minimum(xs + 10, W - 1)] & (xs + 10 < W)
        right[y] = np.where(on, body[y, xs + 10], bg[y, xs + 6])
    return left.round().astype(np.uint8), right.round().astype(np.uint8), own


def test_the_background_between_a_figures_legs_stays_out_of_its_match() -> None:
    left, right, own = _walker_before_hedge()
    filled = np.zeros_like(own)
    filled[10:70, X0:X0 + 26] = True  # the outline with the gap between the legs filled in
    # neither the temporal model nor eq. (9) sees the background in the gap change
    mask = seen_changed(filled, own, own)
    assert np.array_equal(mask, own)
    window = (slice(10, 70), slice(X0, X0 + 26))
    whole = refine_region(left, right, filled[window], X0, 10, 10.0, min_score=0.0, robust=False)  # least squares
    seen = refine_region(left, right, mask[window], X0, 10, 10.0, min_score=0.0)
    assert whole is not None and seen is not None
    assert abs(whole.disparity - 10.0) > 0.2  # pulled towards the background's 6 px
    assert abs(seen.disparity - 10.0) < 0.01 and seen.score > 0.99


def test_a_mask_mostly_unseen_is_matched_whole() -> None:
    """Where what either test sees change is under half the mask, that is too little to match on."""
    mask = np.ones((20, 20), bool)
    seen = np.zeros_like(mask)
    seen[:9] = True  # 45 %
    assert np.array_equal(seen_changed(mask, seen, np.zeros_like(mask)), mask)
    seen[9] = True  # 50 %, by either test
    assert np.array_equal(seen_changed(mask, seen, np.zeros_like(mask)), seen)
    assert np.array_equal(seen_changed(mask, np.zeros_like(mask), seen), seen)
