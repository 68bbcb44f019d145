"""The simulated rig's true cameras: two pinhole cameras with lens distortion, optical axes parallel (§3)."""

from __future__ import annotations

import numpy as np

from tracker.geometry import Camera, StereoRig

BASELINE_M = 0.30
FOCAL_AT_640 = 600.0
# Brown-Conrady k1 k2 p1 p2 k3 of the two simulated lenses (a typical webcam's barrel distortion).
DIST_LEFT = np.array([-0.12, 0.05, 0.0006, -0.0004, 0.0])
DIST_RIGHT = np.array([-0.11, 0.045, -0.0003, 0.0005, 0.0])


def default_rig(size: tuple[int, int] = (640, 480), baseline_m: float = BASELINE_M) -> StereoRig:
    """The simulator's ground-truth rig for an image `size` (width, height): f scales with width
    (600 px at 640 wide), principal points a little off centre, baseline along the rig's x axis."""
    w, h = size
    f = FOCAL_AT_640 * w / 640.0
    s = w / 640.0
    K_l = np.array([[f, 0.0, w / 2 - 1.5 * s], [0.0, f * 1.001, h / 2 + 2.0 * s], [0.0, 0.0, 1.0]])
    K_r = np.array([[f * 1.002, 0.0, w / 2 + 2.5 * s], [0.0, f * 1.003, h / 2 - 1.0 * s], [0.0, 0.0, 1.0]])
    half = np.array([baseline_m / 2, 0.0, 0.0])
    left = Camera(K_l, DIST_LEFT.copy(), (w, h), np.eye(3), -half)
    right = Camera(K_r, DIST_RIGHT.copy(), (w, h), np.eye(3), half)
    return StereoRig(left, right)
