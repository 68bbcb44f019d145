"""Work cut from the per-frame tail (moving-camera correspondence maps, ...) gives the same results as the
direct computation."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from tracker.bgdepth import BackgroundDepth, CorrespondenceMap, _distort_points
from tracker.frames import GimbalState
from tracker.geometry import Camera, gimbal_rotation
from tracker.pipeline import Pipeline
from tracker.sim.scenarios import SimRig, get_scenario


def _direct(bg: BackgroundDepth, key: int, gimbal: GimbalState, box: tuple[int, int, int, int]
            ) -> CorrespondenceMap:
    """The correspondence map of a box written out plainly (canvas lookup, ray to the other camera,
    Camera.distort_normalized), as the reference for the optimised one."""
    x0, y0, x1, y1 = box
    rays = bg.rays[key][y0:y1, x0:x1]
    K = np.array([[bg.f, 0.0, bg.cx], [0.0, bg.f, bg.cy], [0.0, 0.0, 1.0]])
    h = cv2.transform(rays, (K @ gimbal_rotation(gimbal.pan_deg, gimbal.tilt_deg)).astype(np.float32))
    pu, pv = cv2.divide(h[..., 0], h[..., 2]), cv2.divide(h[..., 1], h[..., 2])
    inv = cv2.remap(bg.canvas, pu, pv, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0.0)
    floor = cv2.remap(bg.floors[key], pu, pv, cv2.INTER_NEAREST, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    rig = bg.rect.rig
    cam_k, cam_o = (rig.left, rig.right) if key == 0 else (rig.right, rig.left)
    valid = inv > 0
    t = 1.0 / np.where(valid, inv, 1.0).astype(np.float64) - rays.astype(np.float64) @ cam_k.c
    X = cam_k.c + t[..., None] * rays  # rig frame
    Xo = (X - cam_o.c) @ cam_o.R_rc.T
    mx, my = cam_o.distort_normalized(Xo[..., 0] / Xo[..., 2], Xo[..., 1] / Xo[..., 2])
    W, H = cam_o.size
    valid &= (Xo[..., 2] > 0) & (mx >= 0) & (my >= 0) & (mx <= W - 1) & (my <= H - 1)
    r3 = (bg.rect.R1 @ rig.left.R_rc)[2]
    disp = bg.rect.f * bg.rect.b / np.maximum((X - rig.left.c) @ r3, 1e-3)
    return CorrespondenceMap(mx.astype(np.float32), my.astype(np.float32), valid, disp.astype(np.float32), floor)


@pytest.fixture(scope="module")
def pipe() -> Pipeline:
    sim = SimRig(get_scenario("pan"), seed=0)
    p = Pipeline(sim.rig)
    p.learn_background(sim.background())
    return p


def test_distortion_in_place_equals_the_camera_model() -> None:
    rng = np.random.default_rng(1)
    cam = Camera(np.array([[600.0, 0.4, 318.5], [0.0, 600.6, 242.0], [0.0, 0.0, 1.0]]),
                 np.array([-0.12, 0.05, 0.0006, -0.0004, 0.01]), (640, 480))
    xyz = [rng.uniform(-1.0, 1.0, (40, 50)).astype(np.float32) for _ in range(2)]
    z = rng.uniform(1.0, 9.0, (40, 50)).astype(np.float32)
    want = cam.distort_normalized(xyz[0] / z, xyz[1] / z)
    got = _distort_points(cam, xyz[0].copy(), xyz[1].copy(), z)
    for g, w in zip(got, want, strict=True):
        assert g.dtype == np.float32 and np.allclose(g, w, rtol=0.0, atol=1e-3)


@pytest.mark.parametrize("key", [0, 1])
def test_moving_pose_maps_equal_the_direct_computation(pipe: Pipeline, key: int) -> None:
    for g in (GimbalState(0.0, 0.0), GimbalState(-7.3, 2.1), GimbalState(12.6, -4.4)):
        for box in ((100, 90, 180, 200), (0, 0, 64, 48), (500, 300, 640, 480)):
            got = pipe.bg.correspondence(key, g, box=box)
            want = _direct(pipe.bg, key, g, box)
            assert np.array_equal(got.floor, want.floor)
            both = got.valid & want.valid
            assert np.count_nonzero(got.valid ^ want.valid) <= 2  # a pixel on the image's edge, at most
            for name in ("map_x", "map_y"):
                assert np.allclose(getattr(got, name)[both], getattr(want, name)[both], atol=2e-3)
            assert np.allclose(got.disparity[both], want.disparity[both], rtol=1e-4)


def test_lazy_maps_map_only_the_missing_pixels_and_equal_direct_maps(pipe: Pipeline) -> None:
    sub = pipe.subtractor
    g = GimbalState(3.3, -1.2)
    sub.maps(g)
    sub.moving = False
    boxes = [(100, 90, 118, 104), (110, 95, 160, 130), (100, 90, 118, 104), (0, 0, 640, 20)]
    area = 0
    for box in boxes:
        for key in (0, 1):
            got = sub.correspondence(key, g, box)
            want = pipe.bg.correspondence(key, g, box=box)
            assert np.array_equal(got.valid, want.valid) and np.array_equal(got.floor, want.floor)
            for name in ("map_x", "map_y", "disparity"):
                assert np.allclose(getattr(got, name), getattr(want, name), atol=1e-3)
        if box == boxes[0] and area == 0:
            area = int(sub.maps(g).full[0].done.sum())
            assert area == 18 * 14  # the box itself, not the 32-pixel tiles around it
    done = sub.maps(g).full[1].done
    assert done[90:104, 100:118].all() and done[95:130, 110:160].all() and done[:20].all()
    assert not done[200:].any()


def test_small_untracked_regions_are_not_verified_while_the_cameras_move(pipe: Pipeline) -> None:
    ver, cfg = pipe.verifier, pipe.subtractor.cfg
    least = cfg.moving_min_cells * cfg.stride * cfg.stride  # what a candidate box needs while moving
    pipe.subtractor.moving = True
    assert ver._too_small_to_be_new(least - 1, None)
    assert not ver._too_small_to_be_new(least, None)
    assert not ver._too_small_to_be_new(least - 1, 12.5)  # a track is predicted there: verified
    pipe.subtractor.moving = False
    assert not ver._too_small_to_be_new(least - 1, None)  # cameras still: every region is verified
