"""Where the temporal picture decides the rim (tracker.rim): a part at the background's depth that only the
learnt background tells from it joins; the ground between two parts of a body, where neither key's test can
be made, stays out where the learnt background explains it; and a learnt background off all round the object
(a wrong gain) decides nothing."""

from __future__ import annotations

import cv2
import numpy as np

from tracker.rim import Pictures, RimConfig, along_rows, recover_rim, recover_rim_keys

H, W = 90, 120


def _u8(a: np.ndarray) -> np.ndarray:
    return np.clip(a, 0, 255).astype(np.uint8)


def _ground(rng: np.random.Generator, amp: float) -> np.ndarray:
    t = cv2.GaussianBlur(rng.normal(0.0, 1.0, (H, W)).astype(np.float32), (0, 0), 1.5)
    return 110.0 + amp * t / t.std()


def _foot_scene(offset: float = 0.0):  # type: ignore[no-untyped-def]
    """A disc (radius 25 px) of its own texture whose lower right quarter (the foot) looks like the ground
    behind it but for a texture of its own, ±3 grey levels: the body stands at the ground's depth there, so the
    right image at the body's disparity and at the ground's show nearly the same (the ground's picture off
    by ±1.5 levels, as a background matched a pixel or two away is). Returns the pictures (the learnt
    background off by `offset` levels everywhere: a wrong gain), the disc and the foot."""
    rng = np.random.default_rng(3)
    yy, xx = np.mgrid[0:H, 0:W]
    disc = np.hypot(xx - 60.0, yy - 40.0) <= 25.0
    foot = disc & (yy >= 50) & (xx >= 60)  # the other foot, lit, keeps the outline's box to the ground
    ground = _ground(rng, 10.0)
    body = 150.0 + 20.0 * rng.normal(0.0, 1.0, (H, W))
    seen = np.where(foot, ground + rng.choice([-3.0, 3.0], size=(H, W)), np.where(disc, body, ground))
    noise = lambda: rng.normal(0.0, 0.8, (H, W))  # noqa: E731
    left = seen + noise()
    right_obj = seen + noise()
    right_bg = np.where(disc & ~foot, ground, seen + rng.choice([-1.5, 1.5], size=(H, W))) + noise()
    pics = Pictures(_u8(left), [_u8(right_obj)], _u8(right_bg), _u8(ground + offset), RimConfig().window_px)
    return pics, disc, foot


def test_a_foot_at_the_grounds_depth_joins_where_the_learnt_background_says_body() -> None:
    """The stereo pictures cannot tell the foot from the ground (C_s within noise of C_o), the learnt
    background can (C_t - C_o about 3 levels a pixel over the window): three quarters of the foot join and the
    ground beside it, which the learnt background explains, does not. With model_margin 0 (the temporal
    picture never deciding alone) the foot stays out."""
    pics, disc, foot = _foot_scene()
    obj = disc & ~foot
    out = recover_rim(obj, pics, np.ones_like(disc), RimConfig())
    assert np.count_nonzero(out & foot) > 0.65 * np.count_nonzero(foot)  # 203 of 267 px: its rim's windows see ground
    assert np.count_nonzero(out & ~disc) <= 8
    off = recover_rim(obj, pics, np.ones_like(disc), RimConfig(model_margin=0))
    assert np.count_nonzero(off & foot) < 0.1 * np.count_nonzero(foot)


def test_a_learnt_background_off_all_round_decides_nothing() -> None:
    """With the learnt background 8 levels off everywhere (a gain taken on a skewed ring), it says body for
    the ground as well: it does not decide, and neither the foot nor the ground joins."""
    pics, disc, foot = _foot_scene(offset=8.0)
    out = recover_rim(disc & ~foot, pics, np.ones_like(disc), RimConfig())
    assert np.count_nonzero(out & ~disc) <= 8 and np.count_nonzero(out & foot) < 0.1 * np.count_nonzero(foot)


def test_the_ground_between_two_legs_stays_out_where_the_learnt_background_explains_it() -> None:
    """Two legs 6 px apart, Δd = 8 px: for the smooth ground between them each key's test lands on a leg
    (the right camera sees a leg where its background would be, and the left key's background pixel is the
    other leg), so neither can be made, and the ground matches the legs' picture. Without the learnt
    background the gap joins; with it (the ground unchanged) it stays out, and the legs' own lost edge,
    unlike the ground, still joins."""
    rng = np.random.default_rng(5)
    yy, xx = np.mgrid[0:H, 0:W]
    legs = ((xx >= 40) & (xx < 57) | (xx >= 63) & (xx < 80)) & (yy >= 20) & (yy < 75)
    gap = (xx >= 57) & (xx < 63) & (yy >= 20) & (yy < 75)
    edge = legs & (xx >= 76)  # the right leg's outer edge, lost
    ground = _ground(rng, 1.0)
    seen = np.where(legs, 150.0 + 20.0 * rng.normal(0.0, 1.0, (H, W)), ground)
    left = seen + rng.normal(0.0, 0.8, (H, W))
    right_obj = seen + rng.normal(0.0, 0.8, (H, W))
    useless = _u8(255 - left)  # stereo pictures of the background that explain nothing
    ahead, behind = along_rows(legs.shape, np.full(legs.shape, 8.0, np.float32))
    args = (useless, ahead, behind, np.ones_like(legs), RimConfig(), 12)
    obj = legs & ~edge
    free = recover_rim_keys(obj, Pictures(_u8(left), [_u8(right_obj)], useless, None, 5), *args)
    learnt = _u8(np.where(legs, 255 - seen, ground))  # a mean over many frames: the legs not in it
    kept = recover_rim_keys(obj, Pictures(_u8(left), [_u8(right_obj)], useless, learnt, 5), *args)
    assert np.count_nonzero(free & gap) > 0.8 * np.count_nonzero(gap)
    assert np.count_nonzero(kept & gap) < 0.1 * np.count_nonzero(gap)
    assert np.count_nonzero(kept & edge) > 0.8 * np.count_nonzero(edge)
