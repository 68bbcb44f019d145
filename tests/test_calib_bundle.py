"""Bundle adjustment on synthetic corners: the Euler singularity (φ = 90°) and outlier views."""

from __future__ import annotations

import numpy as np

from calibration.board import BoardSpec
from calibration.bundle import project_points, rodrigues
from calibration.stereo import ViewSet, calibrate_stereo
from tracker.geometry import euler_to_matrix

BOARD = BoardSpec(9, 6, 0.05)
INTR = np.array([[600.0, 600.6, 318.5, 242.0, -0.12, 0.05, 6e-4, -4e-4, 0.0],
                 [601.2, 601.8, 322.5, 239.0, -0.11, 0.045, -3e-4, 5e-4, 0.0]])


def _views(R: np.ndarray, T: np.ndarray, centre: np.ndarray, normal: np.ndarray, n: int, seed: int) -> ViewSet:
    """n board views around `centre` (left frame) facing along `normal`, projected in both cameras."""
    rng = np.random.default_rng(seed)
    obj = BOARD.object_points()
    mid = obj.mean(axis=0)
    z = normal / np.linalg.norm(normal)
    x = np.cross([0.0, 1.0, 0.0], z)
    x /= np.linalg.norm(x)
    base = np.stack([x, np.cross(z, x), z], axis=1)
    obs = np.zeros((2, n, BOARD.n_corners, 2))
    for v in range(n):
        Rb = base @ euler_to_matrix(*np.radians(rng.uniform(-25, 25, 3)))
        t = centre + rng.uniform(-0.08, 0.08, 3) - Rb @ mid
        Xl = obj @ Rb.T + t
        obs[0, v] = project_points(INTR[0], Xl) + rng.normal(0, 0.05, (BOARD.n_corners, 2))
        obs[1, v] = project_points(INTR[1], Xl @ R.T + T) + rng.normal(0, 0.05, (BOARD.n_corners, 2))
    return ViewSet(obs, np.ones((2, n), bool), obj, (640, 480), [f"v{v}" for v in range(n)])


def test_stereo_rotation_at_euler_singularity() -> None:
    R = euler_to_matrix(0.3, np.radians(90.0), 0.2)  # φ = 90°: eq. (6) is singular here
    P = np.array([0.0, 0.0, 1.0])
    axis_r = R.T @ np.array([0.0, 0.0, 1.0])  # the right camera's optical axis in the left frame
    T = -R @ (P - 1.0 * axis_r)  # right camera 1 m from P, looking at it
    views = _views(R, T, P, np.array([0.0, 0.0, 1.0]) + axis_r, 16, seed=1)
    cal = calibrate_stereo(views, BOARD)
    assert cal.ba.recentred
    angle = np.degrees(np.arccos(np.clip((np.trace(cal.ba.R.T @ R) - 1) / 2, -1, 1)))
    assert angle < 0.2  # precision-limited (0.05 px noise); a failed solve is off by degrees
    np.testing.assert_allclose(cal.ba.T, T, atol=2e-3)
    np.testing.assert_allclose(euler_to_matrix(*cal.ba.euler), cal.ba.R, atol=1e-9)
    assert abs(np.degrees(cal.ba.euler[1]) - 90.0) < 0.1


def test_outlier_view_is_dropped_with_reason_and_stds_are_reported() -> None:
    R, T = euler_to_matrix(0.01, -0.02, 0.005), np.array([-0.3, 0.002, 0.001])
    views = _views(R, T, np.array([0.15, 0.0, 1.0]), np.array([0.0, 0.0, 1.0]), 12, seed=2)
    views.obs[1, 5] += np.random.default_rng(0).normal(0, 3.0, views.obs[1, 5].shape)
    cal = calibrate_stereo(views, BOARD)
    assert [s.name for s in cal.rejected] == ["v5"]
    assert "outlier" in cal.rejected[0].reason and "px" in cal.rejected[0].reason
    assert cal.ba.rms < 0.1
    np.testing.assert_allclose(cal.ba.intr[:, :4], INTR[:, :4], atol=0.8)
    assert np.all(cal.ba.std_intr[:, :4] > 0) and np.all(cal.ba.std_intr[:, :4] < 1.0)
    assert np.all(cal.ba.std_euler > 0)
    assert not cal.ba.recentred
    np.testing.assert_allclose(rodrigues(np.zeros((1, 3)))[0], np.eye(3))
