"""Start values for the bundle adjustment: Zhang's homography intrinsics, PnP board poses, per-camera
adjustment, then the stereo extrinsics as the chordal mean of the per-view relative poses."""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

from calibration.bundle import N_INTR, BAInput, BAResult, bundle_adjust, intr_matrices, rodrigues

F64 = NDArray[np.float64]
B = NDArray[np.bool_]


def intr_vector(K: F64, dist: F64) -> F64:
    """(3, 3) K and (5,) distortion -> (9,) fx fy cx cy k1 k2 p1 p2 k3."""
    out: F64 = np.r_[K[0, 0], K[1, 1], K[0, 2], K[1, 2], np.asarray(dist, dtype=np.float64)[:5]]
    return out


def solve_pose(obj: F64, pts: F64, intr: F64) -> F64:
    """Board pose (ω (3,), t (3,)) in the camera frame from corners (N, 2) px, by cv2.solvePnP."""
    K, dist = intr_matrices(intr)
    ok, rvec, tvec = cv2.solvePnP(obj, pts, K, dist, flags=cv2.SOLVEPNP_ITERATIVE)
    if not ok:
        ok, rvec, tvec = cv2.solvePnP(obj, pts, K, dist, flags=cv2.SOLVEPNP_SQPNP)
    out: F64 = np.r_[np.asarray(rvec, dtype=np.float64).ravel(), np.asarray(tvec, dtype=np.float64).ravel()]
    return out


def calibrate_mono(obj: F64, obs: F64, size: tuple[int, int], fixed: B, loss: str = "huber") -> BAResult:
    """One camera: obs (V, N, 2) px of the board obj (V, N, 3) -> bundle-adjusted intrinsics and poses."""
    V = obs.shape[0]
    K0 = cv2.initCameraMatrix2D(
        [o.astype(np.float32) for o in obj], [o.astype(np.float32) for o in obs], size, aspectRatio=0.0
    )
    intr = intr_vector(np.asarray(K0, dtype=np.float64), np.zeros(5))
    poses = np.array([solve_pose(X, o, intr) for X, o in zip(obj, obs, strict=True)])
    inp = BAInput(obj, obs[None], np.ones((1, V), dtype=bool), intr[None], poses, np.eye(3), np.zeros(3),
                  fixed, loss=loss)
    return bundle_adjust(inp)


def mean_rotation(Rs: F64) -> F64:
    """Chordal L2 mean of rotations (M, 3, 3): the rotation nearest their sum (SVD projection)."""
    U, _, Vt = np.linalg.svd(np.sum(Rs, axis=0))
    D = np.diag([1.0, 1.0, float(np.sign(np.linalg.det(U @ Vt)))])
    out: F64 = U @ D @ Vt
    return out


def init_stereo(
    obj: F64, obs: F64, seen: B, size: tuple[int, int], fixed: B, loss: str = "huber"
) -> BAInput:
    """Start values for the joint adjustment: obs (2, V, N, 2), seen (2, V). Each camera is calibrated
    alone; obj (V, N, 3); R0, T0 come from the views both cameras see; every view's pose is expressed
    in the left frame."""
    mono = [calibrate_mono(obj[seen[c]], obs[c][seen[c]], size, fixed, loss) for c in range(2)]
    V = seen.shape[1]
    pose = np.full((2, V, 6), np.nan)
    for c in range(2):
        pose[c][seen[c]] = mono[c].poses
    both = seen[0] & seen[1]
    if not both.any():
        raise ValueError("no view shows the board in both cameras: cannot relate the two cameras")
    Rl, Rr = rodrigues(pose[0][both, :3]), rodrigues(pose[1][both, :3])
    Rrel = Rr @ np.transpose(Rl, (0, 2, 1))  # x_r = R x_l + T per view
    R0 = mean_rotation(Rrel)
    T0 = np.median(pose[1][both, 3:] - np.einsum("ij,vj->vi", R0, pose[0][both, 3:]), axis=0)
    poses = pose[0].copy()
    only_r = seen[1] & ~seen[0]
    for v in np.flatnonzero(only_r):  # left-frame pose from the right one: x_l = R0ᵀ (x_r - T0)
        Rv = rodrigues(pose[1][v : v + 1, :3])[0]
        rvec, _ = cv2.Rodrigues(R0.T @ Rv)
        poses[v] = np.r_[rvec.ravel(), R0.T @ (pose[1][v, 3:] - T0)]
    intr = np.stack([m.intr[0] for m in mono])
    return BAInput(obj, obs, seen, intr, poses, R0, T0, fixed, loss=loss)


def default_fixed(fix_k3: bool = False) -> B:
    """Mask (9,) of intrinsics held fixed: only k3 when `fix_k3` (a 4-coefficient lens like Bouguet's)."""
    fixed = np.zeros(N_INTR, dtype=bool)
    fixed[8] = fix_k3
    return fixed
