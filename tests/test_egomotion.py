"""tracker.egomotion: the mount's own turning taken out of the tracks' image states (the simulated rig's
cameras, with their lens distortion and their offset from the pivot)."""

from __future__ import annotations

import numpy as np

from tracker.egomotion import PoseCompensation
from tracker.frames import GimbalState
from tracker.geometry import gimbal_rotation
from tracker.sim.rig import default_rig
from tracker.tracks import MultiTracker

RIG = default_rig()


def pixel(W: np.ndarray, g: GimbalState) -> np.ndarray:
    """(x, y, 20) of world point W (m, pivot at the origin) in the left camera at pose g."""
    X_rig = W @ gimbal_rotation(g.pan_deg, g.tilt_deg)  # R_world_rigᵀ W, as rows
    return np.array([[*RIG.left.project(X_rig[None])[0], 20.0]])


def test_a_static_point_keeps_its_home_pixel_however_the_mount_turns() -> None:
    ego = PoseCompensation(RIG.left)
    home = GimbalState(0.0, 0.0)
    for W in (np.array([1.0, 0.5, 10.0]), np.array([-2.0, -0.4, 6.0]), np.array([3.0, 1.0, 25.0])):
        for g in (GimbalState(-5.0, 0.0), GimbalState(8.0, -4.0), GimbalState(-12.0, 3.0)):
            raw = pixel(W, g)
            seen = ego.to_home(raw, g)
            moved = float(np.hypot(*(raw - pixel(W, home))[0, :2]))
            assert moved > 30.0  # the turn alone moves it by tens of pixels
            assert np.hypot(*(seen - pixel(W, home))[0, :2]) < 4.0  # to within 4 px: lens distortion, pivot offset
            assert seen[0, 2] == raw[0, 2]
            assert np.allclose(ego.from_home(seen, g), raw, atol=1e-9)


def test_home_or_no_mount_is_the_identity() -> None:
    ego = PoseCompensation(RIG.left)
    pts = np.array([[100.0, 200.0, 12.0], [300.5, 10.25, 3.0]])
    assert ego.to_home(pts, None) is pts and ego.to_home(pts, GimbalState(0.0, 0.0)) is pts
    assert ego.from_home(np.zeros((0, 3)), GimbalState(5.0, 1.0)).shape == (0, 3)


def test_a_slew_towards_a_still_target_keeps_its_track() -> None:
    """The mount turns 30° in 6 frames towards a target standing still, then stops: in raw pixels the
    target sweeps across the image and the constant-velocity prediction overshoots when the mount stops
    (a new track); as seen at home it stands still and keeps its track."""
    ego = PoseCompensation(RIG.left)
    W = np.array([-5.0, 0.2, 10.0])
    poses = [GimbalState(-5.0 * min(k, 6), 0.0) for k in range(12)]
    raw_ids, home_ids = [], []
    raw, comp = MultiTracker(), MultiTracker()
    for k, g in enumerate(poses):
        if k == 6:
            continue  # the frame the mount stops in: the target not found (as in the live run)
        obs = pixel(W, g)
        raw_ids += raw.update(k / 30.0, obs)
        home_ids += comp.update(k / 30.0, ego.to_home(obs, g))
    assert len(set(home_ids)) == 1
    assert len(set(raw_ids)) > 1
