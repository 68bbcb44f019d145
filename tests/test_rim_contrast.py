"""The outline's 1-σ from its rim's contrast (tracker.rim_contrast): a rim that stands out from the temporal
model has no such term, a side whose rim is faint has side_px times its faint share, and the localiser takes
that in place of the solid prior's fixed rim term. A faint side's lost band is undone (rim_shift_px): the
centroid moves towards the faint side, and its 1-σ is then the spread left."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
from sim_helpers import run_frames

from tracker.localize import Localizer
from tracker.rectify import Rectifier
from tracker.rim_contrast import RimContrastConfig, faint_shares, grown_shift_y, rim_shift_px, rim_sigma_px
from tracker.sim.rig import default_rig
from tracker.solid_prior import SolidPrior

CFG = RimContrastConfig()


def _disc(right_grey: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple[int, int, int, int]]:
    """A textured wall (B), and the frame: a disc of radius 20 px at grey 200 whose right half is
    `right_grey`, on that wall; its mask over its box."""
    rng = np.random.default_rng(3)
    wall = rng.normal(90.0, 6.0, (120, 160)).clip(0, 255).astype(np.float32)
    frame = wall.astype(np.uint8).copy()
    cv2.circle(frame, (80, 60), 20, 200, -1)
    half = np.zeros_like(frame)
    cv2.circle(half, (80, 60), 20, 1, -1)
    half[:, :81] = 0
    frame[half > 0] = right_grey
    box = (58, 38, 103, 83)
    mask = np.zeros((box[3] - box[1], box[2] - box[0]), np.uint8)
    cv2.circle(mask, (80 - box[0], 60 - box[1]), 20, 1, -1)
    return frame, wall, mask.astype(bool), box


def test_a_rim_that_stands_out_adds_nothing() -> None:
    frame, wall, mask, box = _disc(200)
    shares = faint_shares(mask, box, frame, wall, 1.0, CFG)
    assert max(shares) < 0.02
    assert max(rim_sigma_px(shares, CFG)) < 0.02


def test_a_faint_side_widens_its_axis_by_half_its_term() -> None:
    frame, wall, mask, box = _disc(100)  # the right half 10 grey levels off the wall: under 2 ε
    left, right, top, bottom = faint_shares(mask, box, frame, wall, 1.0, CFG)
    assert right > 0.9 and left < 0.02
    assert 0.2 < top < 0.8 and 0.2 < bottom < 0.8  # their right halves
    sx, sy = rim_sigma_px((left, right, top, bottom), CFG)
    assert math.isclose(sx, math.hypot(CFG.side_px * left, CFG.side_px * right) / 2.0, rel_tol=1e-9)
    assert 0.4 * CFG.side_px < sx < 0.51 * CFG.side_px and sy < sx
    # at the frame's gain: the same wall under light 1.5 times as bright, the disc's right half too
    bright = (frame.astype(np.float32) * 1.5).clip(0, 255).astype(np.uint8)
    assert faint_shares(mask, box, bright, wall, 1.5, CFG)[1] > 0.9
    assert faint_shares(mask, box, bright, wall, 1.0, CFG)[1] < 0.5  # the model's gain left out: wrong


def _shaded_ball(falloff_px: float) -> tuple[np.ndarray, np.ndarray, tuple[float, float]]:
    """A ball of radius 20 px at (80.3, 60.6) on a plain wall at grey 90, lit from the left: grey 190 but
    within falloff_px of its right rim, where it darkens linearly to the wall's grey (a shaded limb). The
    frame (120, 160) uint8, the wall B (float32) and the true disc's centroid (x, y)."""
    ys, xs = np.mgrid[0:120, 0:160].astype(np.float64)
    cx, cy, r = 80.3, 60.6, 20.0
    dist = np.hypot(xs - cx, ys - cy)
    inside = dist <= r
    to_rim = r - dist  # px from the rim along the radius
    right = np.clip((xs - cx) / r, 0.0, 1.0)  # the shade grows towards the right
    shade = np.where(right > 0.3, np.clip(to_rim / falloff_px, 0.0, 1.0), 1.0)
    frame = np.where(inside, 90.0 + 100.0 * shade, 90.0).round().astype(np.uint8)
    true = (float(xs[inside].mean()), float(ys[inside].mean()))
    return frame, np.full((120, 160), 90.0, np.float32), true


def test_a_faint_sides_lost_band_is_undone_towards_it() -> None:
    frame, wall, true = _shaded_ball(6.0)
    box = (50, 30, 111, 91)
    mask = np.abs(frame[30:91, 50:111].astype(np.float32) - wall[30:91, 50:111]) > 12.0  # eq. (9)'s ε
    ys, xs = np.nonzero(mask)
    seen = (50 + float(xs.mean()), 30 + float(ys.mean()))
    assert seen[0] < true[0] - 0.1  # the shaded right rim is lost: the centroid lies left of the ball's
    shares = faint_shares(mask, box, frame, wall, 1.0, CFG)
    assert shares[1] > shares[0] + 0.3
    sx, sy = rim_shift_px(shares, mask, CFG, still=True)  # the learnt background's shares: cameras still
    assert sx > 0.0  # towards the faint side
    assert abs(seen[0] + sx - true[0]) < abs(seen[0] - true[0])
    assert abs(sy) < 0.5 * sx  # top and bottom alike: no move along y to speak of
    assert rim_shift_px(shares, mask, CFG, (False, True), still=True)[0] == 0.0  # a vehicle's flat face: not undone
    # undone, the side's 1-σ is the spread left; not undone, the full one
    assert rim_sigma_px(shares, CFG, (True, True))[0] < rim_sigma_px(shares, CFG)[0]
    # both sides as faint: nothing to undo
    assert rim_shift_px((0.5, 0.5, 0.2, 0.2), mask, CFG, still=True) == (0.0, 0.0)


def test_a_still_bodys_faint_side_loses_a_band_of_fixed_width_along_x_a_share_of_its_size_along_y() -> None:
    shares = (0.0, 1.0, 0.0, 0.0)  # the right side's rim all faint
    small, large = np.ones((20, 20), bool), np.ones((120, 120), bool)
    for mask in (small, large):  # a ball or a person, the cameras still: half the fixed band, whatever its size
        assert rim_shift_px(shares, mask, CFG, still=True)[0] == pytest.approx(0.5 * CFG.band_still_px)
    bottom = [rim_shift_px((0.0, 0.0, 0.0, 1.0), m, CFG, still=True)[1] for m in (small, large)]
    assert bottom[1] == pytest.approx(6.0 * bottom[0]) and bottom[0] == pytest.approx(0.5 * CFG.band_still_y * 20)
    # a person's faint bottom (its lower legs over the ground) loses a band of its own, down
    legs = rim_shift_px((0.0, 0.0, 0.0, 1.0), large, CFG, still=True, person=True)[1]
    assert legs == pytest.approx(0.5 * CFG.person_band_still_y * 120) and legs > bottom[1]
    # the cameras moving (the stereo residual's shares): a share of the size, along y alone
    assert rim_shift_px(shares, large, CFG) == (0.0, 0.0)
    assert rim_shift_px((0.0, 0.0, 0.0, 1.0), large, CFG)[1] == pytest.approx(0.5 * CFG.band[1] * 120)
    # and the spread left after it along y is the moving one's; along x a body not wide has the same spread
    # moving or still, a vehicle (not corrected) the full side's
    bottom = (0.0, 0.0, 0.0, 1.0)
    moving_y = rim_sigma_px(bottom, CFG, (True, True), moving=True)[1]
    assert moving_y == pytest.approx(CFG.corrected_side_moving_y_px / 2)
    assert rim_sigma_px(bottom, CFG, (True, True))[1] == pytest.approx(CFG.corrected_side_px[1] / 2)
    assert rim_sigma_px(shares, CFG, (True, True), moving=True)[0] == pytest.approx(CFG.corrected_side_px[0] / 2)
    assert rim_sigma_px(shares, CFG, (True, True))[0] == pytest.approx(CFG.corrected_side_px[0] / 2)
    assert rim_sigma_px(shares, CFG, (False, False), moving=True)[0] == pytest.approx(CFG.side_px / 2)
    assert CFG.corrected_side_px[0] < CFG.side_px


def test_the_localiser_takes_the_rims_sigma_in_place_of_the_fixed_one() -> None:
    rect = Rectifier(default_rig())
    base = (np.array([380.0, 200.0]), 12.0, 0.05, 400, None, (0.0, 0.0), (60.0, 80.0))  # not upright
    loc = Localizer(rect, solid=SolidPrior(upright_sigma=0.0))
    fixed = loc.locate(*base)
    s = SolidPrior().rim_sigma_px / math.sqrt(2.0)
    assert np.allclose(loc.locate(*base, rim_px=(s, s)).cov_world, fixed.cov_world, rtol=1e-12, atol=0.0)
    sharp = loc.locate(*base, rim_px=(0.0, 0.0))
    none = Localizer(rect, solid=SolidPrior(rim_sigma_px=0.0, upright_sigma=0.0)).locate(*base)
    assert np.allclose(sharp.cov_world, none.cov_world, rtol=1e-12, atol=0.0)
    assert fixed.sigma_theta > 1.5 * sharp.sigma_theta and fixed.sigma_phi > 1.5 * sharp.sigma_phi
    faint_x = loc.locate(*base, rim_px=(0.8, 0.0))
    assert faint_x.sigma_theta > fixed.sigma_theta and math.isclose(faint_x.sigma_phi, sharp.sigma_phi, rel_tol=0.05)


def _rim_terms(name: str, frames: int) -> tuple[float, float]:
    """The rim's 1-σ (px, x and y) of the pipeline's target in the last of a scenario's first frames."""
    pipe, sf, res = run_frames(name, frames)
    assert len(res.detections) == 1
    terms = pipe._sigma_terms(sf.frame, res.detections[0].blob, [res.detections[0].blob])
    assert terms.rim_px is not None
    return terms.rim_px


def test_a_lit_sphere_has_a_sharp_rim_and_a_walker_a_faint_one() -> None:
    # approach:body: a sphere at 30 m over a darker hedge, its outline within 0.02 px rms of the truth's
    assert max(_rim_terms("approach:body", 10)) < 0.1
    # walk:body: a textured, shaded walker, its rim fading into the ground and the wall at places
    assert max(_rim_terms("walk:body", 10)) > 0.15


def _stereo_disc(left_grey: float, right_grey: float, d: int = 14, d_bg: int = 4):  # type: ignore[no-untyped-def]
    """An ideal rig (600 px, 0.3 m, no distortion: rectified = raw) before a textured wall at disparity
    d_bg; a disc of radius 20 px at disparity d, its left half at `left_grey`, its right half at
    `right_grey`. The pair, the wall's correspondences over the disc's box, the disc's mask there, the box,
    the rectifier."""
    from tracker.bgdepth import CorrespondenceMap
    from tracker.geometry import Camera, StereoRig

    K = np.array([[600.0, 0.0, 320.0], [0.0, 600.0, 240.0], [0.0, 0.0, 1.0]])
    half = np.array([0.15, 0.0, 0.0])
    rect = Rectifier(StereoRig(Camera(K, np.zeros(5), (640, 480), np.eye(3), -half),
                               Camera(K.copy(), np.zeros(5), (640, 480), np.eye(3), half)))
    rng = np.random.default_rng(5)
    t = cv2.GaussianBlur(rng.normal(0.0, 1.0, (480, 700)).astype(np.float32), (0, 0), 1.5)
    wall = 110.0 + 12.0 * t / t.std()
    yy, xx = np.mgrid[0:480, 0:640]

    def view(dx_bg: int, cx: int) -> np.ndarray:
        img = wall[yy, xx + dx_bg].copy()
        on = np.hypot(xx - cx, yy - 240) <= 20
        img[on & (xx < cx)] = left_grey
        img[on & (xx >= cx)] = right_grey
        return np.clip(img + rng.normal(0.0, 1.2, img.shape), 0, 255).astype(np.uint8)

    left, right = view(0, 320), view(d_bg, 320 - d)
    box = (290, 210, 351, 271)
    x0, y0, x1, y1 = box
    gx, gy = np.meshgrid(np.arange(x0, x1, dtype=np.float32), np.arange(y0, y1, dtype=np.float32))
    shape = gx.shape
    cm = CorrespondenceMap(gx - d_bg, gy, np.ones(shape, bool), np.full(shape, d_bg, np.float32),
                           np.zeros(shape, np.uint8))
    mask = np.hypot(gx - 320, gy - 240) <= 20
    return left, right, cm, mask, box, rect


def test_with_the_cameras_moving_each_side_of_the_rim_is_tested_against_the_background_behind_it() -> None:
    # the left half at the wall's grey: faint, found by the right key where the left key lands on the disc
    # itself (the right camera sees the disc where the left rim's background would be); the bright right
    # half, tested by the left key (eq. 9), stands out
    from tracker.rim_contrast import faint_shares_of, stereo_residual

    left, right, cm, mask, box, rect = _stereo_disc(110.0, 200.0)
    res, tested = stereo_residual(left, right, box, mask, 14.0, cm, rect)
    rim = mask & (cv2.erode(mask.view(np.uint8), np.ones((3, 3), np.uint8), borderValue=0) == 0)
    assert tested[rim].all() and not tested[25:36, 25:36].any()  # the middle: both keys land on the disc
    l_share, r_share, top, bottom = faint_shares_of(mask, res, tested, CFG)
    assert l_share > 0.8 and r_share < 0.02
    assert 0.3 < top < 0.7 and 0.3 < bottom < 0.7  # their left halves
    sx, sy = rim_sigma_px((l_share, r_share, top, bottom), CFG)
    assert sx > 0.4 * CFG.side_px and sy < sx
    # both halves bright: no side faint; the left key alone would have called the left half faint (the
    # disc compared with itself, 10 px over)
    left, right, cm, mask, box, rect = _stereo_disc(200.0, 200.0)
    res, tested = stereo_residual(left, right, box, mask, 14.0, cm, rect)
    assert max(faint_shares_of(mask, res, tested, CFG)) < 0.02
    eq9 = np.abs(left[box[1]:box[3], box[0]:box[2]].astype(np.float32) - cm.warp(right).astype(np.float32))
    assert faint_shares_of(mask, eq9, np.ones_like(mask), CFG)[0] > 0.8


def test_with_the_background_as_deep_as_the_object_its_rim_cannot_be_told_and_counts_as_faint() -> None:
    from tracker.rim_contrast import faint_shares_of, stereo_residual

    left, right, cm, mask, box, rect = _stereo_disc(200.0, 200.0, d=14, d_bg=14)  # the ground at its feet
    res, tested = stereo_residual(left, right, box, mask, 14.0, cm, rect)
    assert tested.all() and min(faint_shares_of(mask, res, tested, CFG)) > 0.99


def test_a_raw_shift_is_carried_into_rectified_pixels_by_the_local_jacobian() -> None:
    rect = Rectifier(default_rig())
    L = rect.rig.left

    def rect_of(u: float, v: float) -> np.ndarray:  # through the lens model, not the map
        ray = L.rays_rig(np.array([u]), np.array([v]))[0]
        x, y, _ = rect.rig_to_rect((L.c + 10.0 * ray)[None, :])
        return np.array([x[0], y[0]])

    for at in ((320.4, 240.2), (12.3, 9.6), (630.5, 470.1)):
        for shift in ((0.7, -0.4), (0.0, 1.2)):
            want = rect_of(at[0] + shift[0], at[1] + shift[1]) - rect_of(*at)
            got = rect.shift_to_rect(np.array(at), shift)
            assert np.allclose(got, want, atol=0.01), (at, shift, got, want)
    assert np.array_equal(rect.shift_to_rect(np.array([5.0, 5.0]), (0.0, 0.0)), np.zeros(2))


def test_a_round_bodys_faint_rows_beyond_its_outline_move_its_centroid() -> None:
    """A body's two bottom rows changed from the background by 6 grey levels (under ε = 12, over the
    4-level floor) lie outside its outline: grown by up to two rings of such pixels the centroid moves down
    by a pixel; by one ring, half that. Pixels changed by ε or more, or within the background's own
    deviation (3 D), are not taken."""
    bg = np.full((40, 40), 100.0, np.float32)
    dev = np.zeros_like(bg)
    image = np.full((40, 40), 100, np.uint8)
    image[10:18, 10:20] = 150  # the outline: rows 10-17
    image[18:20, 10:20] = 106  # its faint rows
    mask, box = np.ones((8, 10), bool), (10, 10, 20, 18)
    assert grown_shift_y(mask, box, image, (bg, dev), 1.0, 12.0, CFG) == pytest.approx(1.0)
    one = RimContrastConfig(grow_rings=1)
    assert grown_shift_y(mask, box, image, (bg, dev), 1.0, 12.0, one) == pytest.approx(0.5)
    strong = image.copy()
    strong[18:20, 10:20] = 112  # changed by ε: eq. (9) would have taken them, so they are something else
    assert grown_shift_y(mask, box, strong, (bg, dev), 1.0, 12.0, CFG) == 0.0
    noisy = dev.copy()
    noisy[18:20] = 3.0  # a background that moves by 3 levels: 6 is within 3 D
    assert grown_shift_y(mask, box, image, (bg, noisy), 1.0, 12.0, CFG) == 0.0
