"""OpenCV's own stereo calibration on the same corners, for comparison with the bundle adjustment."""

from __future__ import annotations

from dataclasses import asdict, dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from calibration.evaluate import rectify
from calibration.stereo import ViewSet
from tracker.geometry import Camera, StereoRig

F64 = NDArray[np.float64]


@dataclass(frozen=True)
class OpenCVReference:
    """cv2.calibrateCamera per camera then cv2.stereoCalibrate (intrinsics refined too) on the views both
    cameras see. stereo_rms_px: RMS over every corner of both cameras (same definition as ours);
    retval: what stereoCalibrate returned; row errors (px) after cv2.stereoRectify; seconds: wall time."""

    stereo_rms_px: float
    retval: float
    rectified_row_error_mean_px: float
    rectified_row_error_rms_px: float
    seconds: float
    rig: StereoRig

    def to_json(self) -> dict[str, float]:
        d = asdict(self)
        d.pop("rig")
        return {k: float(v) for k, v in d.items()}


def opencv_stereo(views: ViewSet) -> OpenCVReference:
    """Calibrate the views' pairs with OpenCV (5-coefficient distortion, no skew)."""
    import time

    t0 = time.perf_counter()
    both = views.seen[0] & views.seen[1]
    obj = [views.obj.astype(np.float32)] * int(both.sum())
    pts = [[p.astype(np.float32) for p in views.obs[c][both]] for c in range(2)]
    crit = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 200, 1e-12)
    mono = [
        cv2.calibrateCamera(obj, pts[c], views.size, None, None, criteria=crit)
        for c in range(2)
    ]
    out = cv2.stereoCalibrate(
        obj, pts[0], pts[1], mono[0][1], mono[0][2], mono[1][1], mono[1][2], views.size, None, None,
        flags=cv2.CALIB_USE_INTRINSIC_GUESS, criteria=crit,
    )
    ret, K1, D1, K2, D2, R, T = out[:7]
    seconds = time.perf_counter() - t0
    left = Camera(np.asarray(K1, np.float64), np.asarray(D1, np.float64).ravel()[:5], views.size)
    right = Camera(np.asarray(K2, np.float64), np.asarray(D2, np.float64).ravel()[:5], views.size)
    rig = StereoRig.from_extrinsics(left, right, np.asarray(R, np.float64), np.asarray(T, np.float64).ravel())
    rms = _stereo_rms(rig, obj[0].astype(np.float64), pts)
    pl = np.concatenate(pts[0]).astype(np.float64)
    pr = np.concatenate(pts[1]).astype(np.float64)
    rect = rectify(rig, pl, pr)
    return OpenCVReference(rms, float(ret), rect.row_error_mean_px, rect.row_error_rms_px, seconds, rig)


def _stereo_rms(rig: StereoRig, obj: F64, pts: list[list[NDArray[np.float32]]]) -> float:
    """RMS reprojection error of OpenCV's solution: each view's left pose by PnP through the left camera,
    the right view through x_r = R x_l + T (as stereoCalibrate models it), both cameras' corners."""
    sq = []
    for pl, pr in zip(pts[0], pts[1], strict=True):
        _, rv, tv = cv2.solvePnP(obj, pl, rig.left.K, rig.left.dist)
        rv, tv = _refine_pair(obj, pl, pr, rig, np.asarray(rv, np.float64), np.asarray(tv, np.float64))
        ql, _ = cv2.projectPoints(obj, rv, tv, rig.left.K, rig.left.dist)
        R_l, _ = cv2.Rodrigues(rv)
        R_r = rig.R @ R_l
        t_r = rig.R @ tv.ravel() + rig.T
        qr, _ = cv2.projectPoints(obj, cv2.Rodrigues(R_r)[0], t_r, rig.right.K, rig.right.dist)
        sq.append(np.sum((ql.reshape(-1, 2) - pl) ** 2, axis=1))
        sq.append(np.sum((qr.reshape(-1, 2) - pr) ** 2, axis=1))
    return float(np.sqrt(np.mean(np.concatenate(sq))))


def _refine_pair(
    obj: F64, pl: NDArray[np.float32], pr: NDArray[np.float32], rig: StereoRig, rv: F64, tv: F64
) -> tuple[F64, F64]:
    """Best board pose for both cameras together with OpenCV's intrinsics and extrinsics held fixed
    (what stereoCalibrate's own error measures), by Gauss-Newton via scipy."""
    from scipy.optimize import least_squares

    def res(p: F64) -> F64:
        R_l, _ = cv2.Rodrigues(p[:3])
        ql, _ = cv2.projectPoints(obj, p[:3], p[3:], rig.left.K, rig.left.dist)
        qr, _ = cv2.projectPoints(
            obj, cv2.Rodrigues(rig.R @ R_l)[0], rig.R @ p[3:] + rig.T, rig.right.K, rig.right.dist
        )
        out: F64 = np.concatenate([(ql.reshape(-1, 2) - pl).ravel(), (qr.reshape(-1, 2) - pr).ravel()])
        return out

    sol = least_squares(res, np.r_[np.ravel(rv), np.ravel(tv)], method="lm")
    return sol.x[:3], sol.x[3:]
