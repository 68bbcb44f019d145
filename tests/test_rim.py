"""The outline's rim recovered by stereo (tracker.rim): a limb that looks like the background to eq. (9) and
the temporal model joins the object; the outline is not fattened; other objects, moving background and
pixels not allowed stay out."""

from __future__ import annotations

import numpy as np
import pytest

from tracker.rim import Pictures, RimConfig, _cost, along_rows, recover_rim, recover_rim_keys

H, W = 90, 120
D_OBJ, D_BG = 12, 4  # px: the object's disparity and the background's


def _texture(rng: np.random.Generator, mean: float, amp: float, shape: tuple[int, int] = (H, W + 40)) -> np.ndarray:
    import cv2

    t = cv2.GaussianBlur(rng.normal(0.0, 1.0, shape).astype(np.float32), (0, 0), 1.2)
    return mean + amp * t / t.std()


def _scene(limb_amp: float, seed: int = 0, textured: bool = True, wide: bool = False):  # type: ignore[no-untyped-def]
    """A disc (radius 25 px) at disparity 12 px before a textured wall at 4 px, as the pictures recover_rim
    compares: left Γ, the right image at the object's disparity and at the background's, and g B. The
    disc's right crescent (its outer 4 px) looks like the wall behind it, off by a texture of its own of
    amplitude limb_amp (grey levels, rms). wide: instead, a bar 21 rows high from the disc's right edge
    in to 11 px from its centre (a part inside the outline's box, as a walker's far leg between its near
    leg and its torso)."""
    rng = np.random.default_rng(seed)
    wall = _texture(rng, 110.0, 18.0)  # the wall in its own (right-image) columns, 40 spare columns
    disc_tex = _texture(rng, 170.0, 25.0 if textured else 0.0)
    limb_tex = _texture(rng, 0.0, limb_amp)
    yy, xx = np.mgrid[0:H, 0:W]
    r = np.hypot(xx - 60.0, yy - 45.0)
    disc = r <= 25.0
    limb = disc & ((r > 11.0) & (abs(yy - 45) <= 10) if wide else (r > 21.0)) & (xx > 60)
    bg_left = wall[:, D_BG:D_BG + W]  # the wall as the left camera sees it: right column x - d_bg
    obj_left = np.where(limb, bg_left + limb_tex[:, :W], disc_tex[:, :W])
    noise = lambda: rng.normal(0.0, 1.5, (H, W))  # noqa: E731
    left = np.where(disc, obj_left, bg_left) + noise()
    # the right image at the object's disparity: the disc where it is, elsewhere the wall 8 px over
    right_obj = np.where(disc, obj_left, wall[:, D_OBJ:D_OBJ + W]) + noise()
    # at the background's disparity: the wall where the disc does not hide it from the right camera
    shifted = np.zeros_like(disc)
    shifted[:, :W - (D_OBJ - D_BG)] = disc[:, D_OBJ - D_BG:]
    right_bg = np.where(shifted, np.roll(obj_left, -(D_OBJ - D_BG), axis=1), bg_left) + noise()
    temporal = bg_left + noise()
    u8 = lambda a: np.clip(a, 0, 255).astype(np.uint8)  # noqa: E731
    return u8(left), u8(right_obj), u8(right_bg), u8(temporal), disc, limb


def _pictures(left: np.ndarray, right_obj: list[np.ndarray], right_bg: np.ndarray,
              temporal: np.ndarray | None) -> Pictures:
    return Pictures(left, right_obj, right_bg, temporal, RimConfig().window_px)


def _missed(left: np.ndarray, temporal: np.ndarray, disc: np.ndarray, eps: int = 12) -> np.ndarray:
    """What the temporal model keeps of the disc: the pixels unlike the background by more than ε."""
    return disc & (np.abs(left.astype(int) - temporal.astype(int)) > eps)


def test_a_limb_with_the_backgrounds_grey_joins_the_object() -> None:
    """The disc's limb differs from the wall behind it by 10 grey levels rms: the temporal model keeps a
    fifth of it; the rim recovers its inner part (the windows of its outer pixels that lie over the wall
    match the wall better), and nothing beyond the disc."""
    left, r_obj, r_bg, temporal, disc, limb = _scene(limb_amp=10.0)
    obj = disc & ~limb
    assert np.count_nonzero(_missed(left, temporal, disc) & limb) < 0.25 * np.count_nonzero(limb)
    out = recover_rim(obj, _pictures(left, [r_obj], r_bg, temporal), np.ones_like(disc), RimConfig())
    assert np.count_nonzero(out & limb) > 0.3 * np.count_nonzero(limb)
    assert not np.any(out & ~disc)
    cx = lambda m: float(np.nonzero(m)[1].mean())  # noqa: E731
    before, after = abs(cx(obj) - cx(disc)), abs(cx(out) - cx(disc))  # 2.6 px -> 1.5 px
    assert before > 2.0 and after < 0.7 * before


def test_a_limb_wider_than_the_band_inside_the_outlines_box_joins() -> None:
    """A bar 21 rows high (more than two bands of 3 px from above and below) that looks like the wall,
    inside the box of what was found: four rounds recover 73 % of it and nothing beyond the disc; one
    round (the band alone) 44 %."""
    left, r_obj, r_bg, temporal, disc, limb = _scene(limb_amp=10.0, wide=True)
    obj = disc & ~limb
    out = recover_rim(obj, _pictures(left, [r_obj], r_bg, temporal), np.ones_like(disc), RimConfig())
    assert np.count_nonzero(out & limb) > 0.65 * np.count_nonzero(limb)
    assert not np.any(out & ~disc)
    once = recover_rim(obj, _pictures(left, [r_obj], r_bg, temporal), np.ones_like(disc), RimConfig(rounds=1))
    assert np.count_nonzero(once & limb) < 0.5 * np.count_nonzero(limb)


@pytest.mark.parametrize("textured", [True, False])
def test_a_whole_outline_is_not_fattened(textured: bool) -> None:
    """A disc seen whole gains at most a few pixels: a centred window beside a bright disc matches the
    disc's disparity better and added about 70 px round this one's perimeter (157 px)."""
    left, r_obj, r_bg, temporal, disc, _ = _scene(limb_amp=25.0, textured=textured)
    out = recover_rim(disc, _pictures(left, [r_obj], r_bg, temporal), np.ones_like(disc), RimConfig())
    assert np.count_nonzero(out & ~disc) <= 8
    assert np.array_equal(out & disc, disc)


def test_pixels_not_allowed_do_not_join() -> None:
    left, r_obj, r_bg, temporal, disc, limb = _scene(limb_amp=10.0)
    obj = disc & ~limb
    allowed = np.ones_like(disc)
    allowed[:45] = False  # another object's pixels, changed pixels, or a background that moves there
    out = recover_rim(obj, _pictures(left, [r_obj], r_bg, temporal), allowed, RimConfig())
    assert not np.any(out[:45] & ~obj[:45]) and np.any(out[45:] & limb[45:])


def test_bad_window_is_refused() -> None:
    with pytest.raises(ValueError, match="window_px must be odd"):
        RimConfig(window_px=4)


def test_without_the_temporal_model_the_stereo_background_holds_all_but_the_shadow() -> None:
    """With a temporal picture that explains nothing, the right image at the background's disparity still
    keeps a whole outline from growing, except into its occlusion shadow (the wall left of the disc that
    the right camera sees the disc in front of): why rim recovery waits for the cameras to stand still."""
    left, r_obj, r_bg, temporal, disc, _ = _scene(limb_amp=25.0)
    useless = (255 - temporal).astype(np.uint8)
    out = recover_rim(disc, _pictures(left, [r_obj], r_bg, useless), np.ones_like(disc), RimConfig())
    grown = out & ~disc
    xs = np.nonzero(grown)[1]
    assert xs.size > 20 and xs.max() < 60  # the shadow side only: left of the disc's centre column


def test_the_object_cost_is_the_least_over_its_pictures() -> None:
    """The object is matched on several pictures (RimRecovery: the right image at d and d (1 ± slant)): a
    limb joins where any of them matches it better than the background; on a picture that matches
    nowhere it does not."""
    left, r_obj, r_bg, temporal, disc, limb = _scene(limb_amp=10.0)
    obj = disc & ~limb
    rng = np.random.default_rng(7)
    other = rng.integers(0, 256, r_obj.shape).astype(np.uint8)  # the right image at a depth that fits nothing
    one = recover_rim(obj, _pictures(left, [r_obj], r_bg, temporal), np.ones_like(disc), RimConfig())
    both = recover_rim(obj, _pictures(left, [other, r_obj], r_bg, temporal), np.ones_like(disc), RimConfig())
    assert np.count_nonzero(one & limb) > 0 and np.array_equal(both, one)
    none = recover_rim(obj, _pictures(left, [other], r_bg, temporal), np.ones_like(disc), RimConfig())
    assert np.array_equal(none, obj)


def test_a_window_past_the_pictures_edge_sums_what_lies_inside() -> None:
    """A pixel at the pictures' edge that a picture matches exactly (difference 0) beside pixels it does not
    (10 grey levels): its best 3x3 window holds its own column and the next, 30 grey levels, not the next
    column twice (OpenCV's mirrored border: 60, as much as the window one column in). Inside, every window
    is whole (90); at the other edge, two columns of it lie inside (60)."""
    diff = np.full((7, 9), 10, np.uint8)
    diff[:, 0] = 0
    cost = _cost(diff, (3, 3))
    assert cost[3, 0] == 30 and cost[3, 4] == 90 and cost[3, 8] == 60


def _moving_scene(seed: int = 0, wall_amp: float = 18.0):  # type: ignore[no-untyped-def]
    """A smooth ball (radius 25 px, 180 grey levels at its middle, lit from the front and above: 80 to 182
    over it) at disparity 12 px before a wall at 4 px (textured, wall_amp grey levels rms): left Γ, the
    right image at the object's disparity Θ(d) and at the background's Θ(d_bg), and Γ(x - Δd), Δd = 8 px;
    the ball's mask and where the left key's test lands on it."""
    rng = np.random.default_rng(seed)
    wall = _texture(rng, 110.0, wall_amp)
    yy, xx = np.mgrid[0:H, 0:W]
    disc = np.hypot(xx - 60.0, yy - 45.0) <= 25.0
    r = np.minimum(np.hypot(xx - 60.0, yy - 45.0) / 25.0, 1.0)
    ball = 100.0 + 80.0 * np.sqrt(1.0 - r * r) - 20.0 * (yy - 45.0) / 25.0  # lit from the front and above
    dd = D_OBJ - D_BG
    bg_left = wall[:, 20:20 + W]  # left column x shows the wall's column x + 20
    noise = lambda: rng.normal(0.0, 1.5, (H, W))  # noqa: E731
    left = np.where(disc, ball, bg_left) + noise()
    # the right camera's column x - d shows the ball, or the wall the left camera sees at x - Δd
    right_obj = np.where(disc, ball, wall[:, 20 - dd:20 - dd + W]) + noise()
    shifted = np.zeros_like(disc)
    shifted[:, :W - dd] = disc[:, dd:]
    right_bg = np.where(shifted, np.roll(ball, -dd, axis=1), bg_left) + noise()
    u8 = lambda a: np.clip(a, 0, 255).astype(np.uint8)  # noqa: E731
    left8 = u8(left)
    return left8, u8(right_obj), u8(right_bg), np.roll(left8, dd, axis=1), disc, shifted


def test_with_the_cameras_moving_a_smooth_balls_lost_side_is_recovered_and_its_shadow_stays_out() -> None:
    """Eq. (9) with the left key tells a smooth ball from the wall only in its right crescent, Δd wide:
    elsewhere the right image at the background's disparity shows the ball itself, Δd over (`shifted`), and
    a shaded side is lost (here its lower cap, 15 rows). Where that is so the background cannot be tested; the
    ball's own match recovers the side (manoeuvre:body, a sphere tracked while the mount turns: pixel F1 0.882
    -> 0.985). The wall beside the ball's left edge, which the right camera cannot see (its shadow), passes the
    left key's test by default and is kept out by the right key's."""
    left, r_obj, r_bg, left_bg, disc, shifted = _moving_scene()
    yy, xx = np.mgrid[0:H, 0:W]
    lost = disc & (yy > 55)
    ahead, behind = along_rows(disc.shape, np.full(disc.shape, float(D_OBJ - D_BG), np.float32))
    out = recover_rim_keys(disc & ~lost, _pictures(left, [r_obj], r_bg, None), left_bg, ahead, behind,
                           np.ones_like(disc), RimConfig(), 12)
    assert np.count_nonzero(out & lost) > 0.9 * np.count_nonzero(lost)
    shadow = shifted & ~disc
    assert np.count_nonzero(out & shadow) <= 3 and np.count_nonzero(out & ~disc) <= 8
    # the still cameras' rule, with no temporal picture that explains anything, recovers little of it
    useless = (255 - left).astype(np.uint8)
    still = recover_rim(disc & ~lost, _pictures(left, [r_obj], r_bg, useless), np.ones_like(disc), RimConfig())
    assert np.count_nonzero(still & lost) < 0.5 * np.count_nonzero(lost)


def test_a_test_counts_as_not_made_only_where_it_lands_a_column_away_on_its_side() -> None:
    """Background pictures that explain everything (each key's test says background): pixels join only
    where both tests count as not made. With Δd = 8 px the lost side of the ball does, between what is
    left of the ball on both sides in its rows; with Δd under a pixel (the background as deep as the ball) or pointing
    the wrong way, the pixel a test lands on is the pixel itself or lies on the wrong side, and nothing
    joins."""
    left, r_obj, _, _, disc, _ = _moving_scene()
    yy, xx = np.mgrid[0:H, 0:W]
    lost = disc & (abs(xx - 60) < 4)  # a strip down the ball's middle, narrower than Δd: ball both sides
    joined = []
    for dd in (8.0, 0.0, -8.0):
        ahead, behind = along_rows(disc.shape, np.full(disc.shape, dd, np.float32))
        out = recover_rim_keys(disc & ~lost, _pictures(left, [r_obj], left, None), r_obj, ahead, behind,
                               np.ones_like(disc), RimConfig(), 12)
        assert not np.any(out & ~disc)
        joined.append(np.count_nonzero(out & lost))
    assert joined[0] > 0.9 * np.count_nonzero(lost) and joined[1:] == [0, 0]


def test_with_the_cameras_still_the_temporal_picture_keeps_a_smooth_wall_out() -> None:
    """Before a smooth wall (1 grey level of texture) the wall matches the ball's disparity as well as its
    own. With stereo pictures of the background that explain nothing (a misregistered background), the
    keys' tests say object all round and the wall joins; the temporal picture of the wall keeps it out
    (walk:plate grew such a fringe on smooth ground: centroid RMSE 0.000 -> 0.085 px without it)."""
    left, r_obj, _, _, disc, _ = _moving_scene(wall_amp=1.0)
    ahead, behind = along_rows(disc.shape, np.full(disc.shape, float(D_OBJ - D_BG), np.float32))
    useless = (255 - left).astype(np.uint8)
    wall = np.where(disc, useless, left).astype(np.uint8)  # the temporal picture: the wall, not the ball
    free = recover_rim_keys(disc, _pictures(left, [r_obj], useless, None), useless, ahead, behind,
                            np.ones_like(disc), RimConfig(), 12)
    kept = recover_rim_keys(disc, _pictures(left, [r_obj], useless, wall), useless, ahead, behind,
                            np.ones_like(disc), RimConfig(), 12)
    assert np.count_nonzero(free & ~disc) > 200 and np.count_nonzero(kept & ~disc) <= 8
    assert np.array_equal(kept & disc, disc)


def _square_scene(frames: int) -> list[tuple[object, np.ndarray]]:
    """Stereo frames (an ideal rig, 600 px focal length, 0.3 m baseline) of a 60 px square at disparity
    12 px moving right by 1 px a frame before a textured wall at 4 px, the first frame empty; the square is
    shaded (20 grey levels brighter in its middle) with a faint texture of its own: eq. (9) passes much of
    it as background where the right image at the wall's disparity shows the square itself, 8 px over.
    With each frame its true left mask."""
    import cv2

    from tracker.frames import StereoFrame

    rng = np.random.default_rng(0)

    def tex(amp: float, blur: float, shape: tuple[int, int]) -> np.ndarray:
        t = cv2.GaussianBlur(rng.normal(0.0, 1.0, shape).astype(np.float32), (0, 0), blur)
        return amp * t / t.std()

    h, w, side = 480, 640, 60
    wall, skin = 110.0 + tex(25.0, 1.5, (h, w + 64)), tex(12.0, 3.0, (side, side))
    yy, xx = np.mgrid[0:h, 0:w]

    def view(x0: int, d_obj: int, d_bg: int, with_square: bool) -> np.ndarray:
        out = wall[yy, xx + d_bg].copy()
        u, v = xx + d_obj - x0, yy - 200
        on = with_square & (u >= 0) & (u < side) & (v >= 0) & (v < side)
        uc, vc = np.clip(u, 0, side - 1), np.clip(v, 0, side - 1)
        shade = 20.0 * (1.0 - np.hypot(uc - side / 2, vc - side / 2) / (side / 2))
        out[on] = (150.0 + shade + skin[vc, uc])[on]
        return np.clip(out + rng.normal(0.0, 1.2, out.shape), 0, 255).astype(np.uint8)

    out = []
    for i in range(frames):
        x0 = 280 + i
        pair = StereoFrame(i, view(x0, 0, 0, i > 0), view(x0, 12, 4, i > 0), i / 30.0, i / 30.0)
        out.append((pair, (xx >= x0) & (xx < x0 + side) & (yy >= 200) & (yy < 200 + side) & (i > 0)))
    return out


def test_a_tracked_shaded_square_is_outlined_whole_with_the_cameras_still() -> None:
    """Tracked with the cameras still, the square's outline is the temporal model's inside the regions of
    both keys of eq. (9) (not the left key's alone) and its parts that the keys' tests could not tell are
    recovered (recover_rim_keys): it covers 99.9 % of the square on average over frames 8 to 15, at least
    99.7 % in each (inside the left key's region alone and without the keys' recovery: 96.4 %, at least
    93.5 %), and nothing beside it."""
    from tracker.geometry import Camera, StereoRig
    from tracker.pipeline import Pipeline

    K = np.array([[600.0, 0.0, 320.0], [0.0, 600.0, 240.0], [0.0, 0.0, 1.0]])
    half = np.array([0.15, 0.0, 0.0])
    rig = StereoRig(Camera(K, np.zeros(5), (640, 480), np.eye(3), -half),
                    Camera(K.copy(), np.zeros(5), (640, 480), np.eye(3), half))
    frames = _square_scene(16)
    pipe = Pipeline(rig)
    pipe.learn_background(frames[0][0])  # type: ignore[arg-type]
    cover, extra = [], 0
    for i, (pair, truth) in enumerate(frames[1:], start=1):
        res = pipe.step(pair)  # type: ignore[arg-type]
        if i >= 8:
            assert [d.track_id for d in res.detections] == [1]
            fg = res.foreground_mask(truth.shape)
            cover.append(np.count_nonzero(fg & truth) / np.count_nonzero(truth))
            extra += int(np.count_nonzero(fg & ~truth))
    assert np.mean(cover) > 0.99 and min(cover) > 0.98 and extra <= 10


def test_the_keys_recovery_keeps_half_a_window_off_the_pictures_edge_and_nothing_for_a_one_pixel_window() -> None:
    from tracker.rim_recovery import off_edges

    m = np.ones((6, 7), bool)
    cut = off_edges(m, 2)
    assert cut[2:4, 2:5].all() and int(cut.sum()) == 2 * 3
    assert off_edges(m, 0).all()  # a 1-px window reaches nothing past its pixel


def test_with_the_cameras_still_a_far_leg_near_the_learnt_grey_joins_where_the_stereo_pictures_decide() -> None:
    """A walker's shaded far leg (walk:body, 3-4 m) is within 2 grey levels a pixel of the learnt background
    over a window, so the temporal picture does not beat the object's by the margin, though both stereo
    pictures of the background are far off: it joins where the background lies a window's width of
    disparity behind (`deep`), and not without that. The wall beside the ball's left edge, the temporal
    picture stale there alike, stays out: the left key's test lands on the ball (its occlusion shadow)."""
    rng = np.random.default_rng(7)
    yy, xx = np.mgrid[0:H, 0:W]
    ball = np.hypot(xx - 60.0, yy - 45.0) <= 25.0
    leg = ball & (xx > 66)  # the part lost, more than a band wide: grown into round by round
    shadow = ~ball & (xx >= 27) & (xx < 35) & (abs(yy - 45) <= 10)  # Δd = 8 px left of the ball
    learnt = _texture(rng, 110.0, 18.0)[:, :W]
    own = rng.choice([-1.4, 1.4], size=(H, W))  # its own texture: 1.4 grey levels off the background
    left = np.where(ball | shadow, learnt + own, learnt) + rng.normal(0.0, 0.8, (H, W))
    right_obj = left + rng.normal(0.0, 0.8, (H, W))  # the object's picture matches it
    other = _texture(rng, 140.0, 25.0)[:, :W]  # the stereo pictures of the background: far off everywhere
    u8 = lambda a: np.clip(a, 0, 255).astype(np.uint8)  # noqa: E731
    pics = _pictures(u8(left), [u8(right_obj)], u8(other), u8(learnt))
    ahead, behind = along_rows(ball.shape, np.full(ball.shape, float(D_OBJ - D_BG), np.float32))
    c_o, c_t = pics.c_o[leg].astype(float), pics.c_t[leg].astype(float)  # type: ignore[union-attr]
    n_w = RimConfig().window_px ** 2
    assert np.median(c_t - c_o) < n_w and np.median(c_t - c_o) > n_w / 2  # between half the margin and it
    deep = np.ones_like(ball)
    args = (u8(other), ahead, behind, np.ones_like(ball), RimConfig(), 12)
    before = recover_rim_keys(ball & ~leg, pics, *args)
    after = recover_rim_keys(ball & ~leg, pics, *args, deep)
    assert np.count_nonzero(before & leg) < 0.1 * np.count_nonzero(leg)
    assert np.count_nonzero(after & leg) > 0.7 * np.count_nonzero(leg)  # 515 of 661 px: 4 px stay out at the edge
    assert np.count_nonzero(after & shadow) == 0 and np.count_nonzero(after & ~ball & ~shadow) <= 8
    shallow = recover_rim_keys(ball & ~leg, pics, *args, np.zeros_like(ball))
    assert np.array_equal(shallow, before)
