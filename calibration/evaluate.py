"""Quality figures: triangulation through either lens model, rectification row error, board coverage."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from calibration.polynomial import PolynomialLens
from tracker.geometry import StereoRig

F64 = NDArray[np.float64]


def _midpoint(dl: F64, dr: F64, R: F64, T: F64) -> F64:
    """Midpoint triangulation in the left camera frame: left rays dl (M, 3) from the origin, right rays
    dr (M, 3) in the right camera frame from its centre -RᵀT. Returns points (M, 3)."""
    c_r = -R.T @ T
    d2 = dr @ R  # right rays in the left frame (Rᵀ applied to rows)
    a, b, c = np.sum(dl * dl, 1), np.sum(dl * d2, 1), np.sum(d2 * d2, 1)
    w = -c_r[None, :]
    d, e = np.sum(dl * w, 1), np.sum(d2 * w, 1)
    den = a * c - b * b
    s = (b * e - c * d) / den
    t = (a * e - b * d) / den
    out: F64 = 0.5 * (s[:, None] * dl + c_r[None, :] + t[:, None] * d2)
    return out


def triangulate_pinhole(rig: StereoRig, pl: F64, pr: F64) -> F64:
    """Distorted pixels (M, 2) in each camera -> points (M, 3) in the left camera frame (metres)."""
    nl = cv2.undistortPoints(pl.reshape(-1, 1, 2), rig.left.K, rig.left.dist).reshape(-1, 2)
    nr = cv2.undistortPoints(pr.reshape(-1, 1, 2), rig.right.K, rig.right.dist).reshape(-1, 2)
    ones = np.ones((len(nl), 1))
    return _midpoint(np.hstack([nl, ones]), np.hstack([nr, ones]), rig.R, rig.T)


def triangulate_polynomial(
    lenses: tuple[PolynomialLens, PolynomialLens], R: F64, T: F64, pl: F64, pr: F64, start: F64
) -> F64:
    """Triangulate with eq. (3)-(4): the ray of a pixel depends on its depth Z_c, so iterate from the
    points `start` (M, 3, left frame): depths -> rays -> midpoint -> depths (converges in a few steps)."""
    X = start.copy()
    for _ in range(6):
        zl = X[:, 2]
        zr = (X @ R.T + T)[:, 2]
        nl = lenses[0].normalized(pl[:, 0], pl[:, 1], zl)
        nr = lenses[1].normalized(pr[:, 0], pr[:, 1], zr)
        ones = np.ones((len(nl), 1))
        X = _midpoint(np.hstack([nl, ones]), np.hstack([nr, ones]), R, T)
    return X


def board_shape_rms(X: F64, obj: F64) -> float:
    """RMS distance (units of obj) between triangulated corners X (N, 3) and the board model obj (N, 3)
    after the best rigid alignment (Kabsch): a truth-free measure of 3-D accuracy."""
    A, B = obj - obj.mean(0), X - X.mean(0)
    U, _, Vt = np.linalg.svd(A.T @ B)
    D = np.diag([1.0, 1.0, float(np.sign(np.linalg.det(U @ Vt)))])
    Rm = (U @ D @ Vt).T
    return float(np.sqrt(np.mean(np.sum((A @ Rm.T - B) ** 2, axis=1))))


@dataclass(frozen=True)
class Rectification:
    """cv2.stereoRectify output and the row error (px) of matched corners after rectification: mean of
    |y_l - y_r| and its RMS. map_left/map_right: (map_x, map_y) float32 (H, W) for cv2.remap."""

    R1: F64
    R2: F64
    P1: F64
    P2: F64
    Q: F64
    row_error_mean_px: float
    row_error_rms_px: float
    map_left: tuple[NDArray[np.float32], NDArray[np.float32]]
    map_right: tuple[NDArray[np.float32], NDArray[np.float32]]


def rectify(rig: StereoRig, pl: F64, pr: F64) -> Rectification:
    """Rectify the rig (alpha 0) and measure the row error of matched corners pl, pr (M, 2) px."""
    size = rig.left.size
    R1, R2, P1, P2, Q, _, _ = cv2.stereoRectify(
        rig.left.K, rig.left.dist, rig.right.K, rig.right.dist, size, rig.R, rig.T.reshape(3, 1), alpha=0.0
    )
    yl = cv2.undistortPoints(pl.reshape(-1, 1, 2), rig.left.K, rig.left.dist, R=R1, P=P1).reshape(-1, 2)
    yr = cv2.undistortPoints(pr.reshape(-1, 1, 2), rig.right.K, rig.right.dist, R=R2, P=P2).reshape(-1, 2)
    dy = yl[:, 1] - yr[:, 1]
    ml = cv2.initUndistortRectifyMap(rig.left.K, rig.left.dist, R1, P1, size, cv2.CV_32FC1)
    mr = cv2.initUndistortRectifyMap(rig.right.K, rig.right.dist, R2, P2, size, cv2.CV_32FC1)
    f64, f32 = np.float64, np.float32
    return Rectification(
        np.asarray(R1, f64), np.asarray(R2, f64), np.asarray(P1, f64), np.asarray(P2, f64),
        np.asarray(Q, f64), float(np.mean(np.abs(dy))), float(np.sqrt(np.mean(dy * dy))),
        (np.asarray(ml[0], f32), np.asarray(ml[1], f32)), (np.asarray(mr[0], f32), np.asarray(mr[1], f32)),
    )


def coverage(corner_sets: list[F64], board_shape: tuple[int, int], size: tuple[int, int]) -> float:
    """Fraction (0-1) of the image area covered by the union of the boards' outlines; corner_sets are
    (rows*cols, 2) px grids, board_shape (cols, rows)."""
    w, h = size
    mask = np.zeros((h, w), np.uint8)
    cols, rows = board_shape
    for c in corner_sets:
        g = c.reshape(rows, cols, 2)
        outline = np.concatenate([g[0, :], g[:, -1], g[-1, ::-1], g[::-1, 0]])
        cv2.fillPoly(mask, [np.round(outline).astype(np.int32)], 1)
    return float(mask.mean())
