from __future__ import annotations

import numpy as np
import pytest

from tracker.frames import GimbalState
from tracker.sim.scenarios import SCENARIOS, SimRig, get_scenario

REQUIRED = {"walk", "illumination", "foliage", "approach", "two-targets", "pan"}


def test_required_scenarios_exist() -> None:
    assert set(SCENARIOS) >= REQUIRED
    with pytest.raises(ValueError, match="unknown scenario 'nope'"):
        get_scenario("nope")


def test_deterministic_for_a_seed() -> None:
    a, b, c = (SimRig(get_scenario("walk"), seed=s) for s in (3, 3, 4))
    for _ in range(3):
        fa, fb, fc = a.step(), b.step(), c.step()
    assert np.array_equal(fa.frame.left, fb.frame.left) and np.array_equal(fa.frame.right, fb.frame.right)
    assert not np.array_equal(fa.frame.left, fc.frame.left)


def test_truth_mask_is_the_image_of_the_plate() -> None:
    # the plate faces the cameras, so in undistorted coordinates the centroid of its pixels is the image of
    # its centre (up to pixel sampling): a check that rendering and ground truth agree
    sim = SimRig(get_scenario("walk"))
    cam = sim.rig.left
    for _ in range(40):
        sf = sim.step()
        tt = sf.truth.target(1)
        assert tt is not None and tt.centroid_left is not None and tt.visible_fraction > 0.9
        v, u = np.nonzero(sf.truth.ids_left == 1)
        xn, yn = cam.undistort_pixels(u.astype(float), v.astype(float))
        # each pixel's area in undistorted coordinates (the lens stretches the grid)
        xa, _ = cam.undistort_pixels(u + 0.5, v.astype(float))
        xb, _ = cam.undistort_pixels(u - 0.5, v.astype(float))
        _, ya = cam.undistort_pixels(u.astype(float), v + 0.5)
        _, yb = cam.undistort_pixels(u.astype(float), v - 0.5)
        w = (xa - xb) * (ya - yb)
        Xc = tt.rig - cam.c
        err_px = cam.f * np.hypot((w * xn).sum() / w.sum() - Xc[0] / Xc[2], (w * yn).sum() / w.sum() - Xc[1] / Xc[2])
        assert err_px < 0.05 + 1.0 / np.sqrt(tt.area_left)
        assert tt.proj_left[0] > tt.proj_right[0]  # positive disparity


def test_illumination_gain_scales_both_images() -> None:
    sim = SimRig(get_scenario("illumination"), noise_sigma=0.0)
    frames = [sim.step().frame for _ in range(75)]
    before, after = frames[55], frames[65]  # gain 1.0 -> 1.3 at t = 2 s
    ratio_l = after.left.astype(float).mean() / before.left.astype(float).mean()
    ratio_r = after.right.astype(float).mean() / before.right.astype(float).mean()
    assert ratio_l == pytest.approx(1.3, abs=0.05) and ratio_r == pytest.approx(1.3, abs=0.05)


def test_gimbal_angles_move_the_image() -> None:
    sim = SimRig(get_scenario("walk"), noise_sigma=0.0)
    home = sim.background(GimbalState(0.0, 0.0))
    panned = sim.background(GimbalState(5.0, 0.0))
    assert not np.array_equal(home.left, panned.left)
    # panning right moves the scene left in the image by about f·tan(5°) ≈ 52 px
    row = 150
    a, b = home.left[row].astype(float), panned.left[row].astype(float)
    shifts = range(30, 80)
    best = min(shifts, key=lambda s: float(np.abs(a[s + 100:500] - b[100:500 - s]).mean()))
    assert 45 <= best <= 60


def test_second_object_and_foreground_ids() -> None:
    sim = SimRig(get_scenario("two-targets"))
    sf = sim.step()
    ids = set(np.unique(sf.truth.ids_left))
    assert {1, 2} <= ids


def test_fast_renderer_matches_exact_ray_casting() -> None:
    from tracker.geometry import gimbal_rotation
    from tracker.sim import cast

    sim = SimRig(get_scenario("foliage"), noise_sigma=0.0)
    view = sim.renderer.views[0]
    R = gimbal_rotation(3.0, -1.0)
    surfaces = [*sim.renderer.static, *(o.surface(0.5, R) for o in sim.objects)]
    assert sim._foliage is not None
    surfaces.append(sim._foliage)
    h, w = 480, 640
    for t in (0.0, 1.3):
        a, b = np.zeros((h, w), np.uint8), np.zeros((h, w), np.uint8)
        da, db = np.full((h, w), np.inf, np.float32), np.full((h, w), np.inf, np.float32)
        ia, ib = np.zeros((h, w), np.uint8), np.zeros((h, w), np.uint8)
        for s in surfaces:
            cast.cast_surface_exact(view, R, s, t, a, da, ia)
            cast.cast_plane_fast(view, R, s, b, db, t, ib)
        diff = np.abs(a.astype(int) - b.astype(int))
        assert (diff > 1).mean() < 1e-4  # a few pixels exactly on an edge may fall either way
        assert (ia != ib).mean() < 1e-4
        finite = np.isfinite(da)
        assert np.array_equal(finite, np.isfinite(db))
        assert np.allclose(da[finite], db[finite], rtol=1e-4)


def test_a_surface_reaching_behind_the_cameras_is_cast_over_its_own_box_only() -> None:
    """pixel_box boxes the part of a surface in front of a camera instead of casting the whole image where
    the surface reaches behind it: a bush wholly behind the cameras (the mount turned away) gets no box,
    and a long moving wall that passes beside the cameras from behind them to 20 m ahead gets a box
    smaller than the image in which the cast draws exactly what the exact ray cast draws in the whole
    image."""
    from tracker.geometry import gimbal_rotation
    from tracker.sim import cast
    from tracker.sim.scene import Surface, smooth_texture

    sim = SimRig(get_scenario("foliage"), noise_sigma=0.0)
    assert sim._foliage is not None
    h, w = 480, 640
    for pan, tilt in ((105.0, 0.0), (160.0, 70.0), (-120.0, 0.0)):
        for view in sim.renderer.views:
            assert cast.pixel_box(view, sim._foliage.corners() @ gimbal_rotation(pan, tilt)) is None
    ex, ey, ez = np.eye(3)
    tex = smooth_texture(np.random.default_rng(3), (120, 900), 2.0, 40, 220)
    wall = Surface("wall", np.array([-2.0, 0.0, 5.0]), ez, ey, 15.0, 2.0, tex, 1.0 / 30, moving=True, target_id=3)
    for pan, tilt in ((0.0, 0.0), (-20.0, 5.0), (20.0, 0.0)):
        R = gimbal_rotation(pan, tilt)
        for view in sim.renderer.views:
            box = cast.pixel_box(view, wall.corners() @ R)
            assert box is not None and box != (0, 0, w, h)
            a, b = np.zeros((h, w), np.uint8), np.zeros((h, w), np.uint8)
            da, db = np.full((h, w), np.inf, np.float32), np.full((h, w), np.inf, np.float32)
            ia, ib = np.zeros((h, w), np.uint8), np.zeros((h, w), np.uint8)
            cast.cast_plane_fast(view, R, wall, a, da, 0.0, ia)  # over pixel_box's box
            cast.cast_surface_exact(view, R, wall, 0.0, b, db, ib)
            x0, y0, x1, y1 = box
            assert not ib[:y0].any() and not ib[y1:].any() and not ib[:, :x0].any() and not ib[:, x1:].any()
            assert np.count_nonzero(ib) > 0 and (ia != ib).mean() < 1e-4, (pan, tilt)
            assert (np.abs(a.astype(int) - b.astype(int)) > 1).mean() < 1e-4
