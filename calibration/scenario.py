"""Calibration against simulated truth: render board views of tracker.sim.rig.default_rig(), detect,
calibrate, and compare with the true cameras (used by `tmeye eval --scenario calibration`).

Corner noise: the views are rendered exactly (tracker.sim.boards, 4x4 anti-aliasing, 1 grey level of
image noise) and the corners detected; the detector's own error against the true projections is
measured, and Gaussian noise is added to the detected corners so that the total per-coordinate error is
`corner_noise_px` (sqrt(σ² - σ_detector²)); the measured total is reported as corner_error_px."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np
from numpy.typing import NDArray

from calibration.board import BoardSpec, detect_board
from calibration.compare import opencv_stereo
from calibration.evaluate import triangulate_pinhole, triangulate_polynomial
from calibration.polynomial import PolynomialLens
from calibration.stereo import StereoCalibration, ViewSet, calibrate_stereo
from tracker.geometry import StereoRig, euler_to_matrix
from tracker.sim.boards import BoardPose, render_board
from tracker.sim.rig import default_rig

F64 = NDArray[np.float64]
BOARD = BoardSpec(9, 6, 0.05)
DISTANCES_M = (0.8, 1.1, 1.5)  # three distances, as the paper's §4 calibration (and eq. 4) needs
HELD_OUT = 8
TILT_DEG = (45.0, 45.0, 20.0)  # largest |δ|, |φ|, |γ| of a board view
SPREAD = (0.36, 0.26)  # board centre x, y within ± this times the distance
MONO_VIEWS = False  # let every other view show the whole board in one camera only
IMAGE_NOISE = 1.0  # grey levels


@dataclass
class ModelFigures:
    """Errors of one model against the truth: focal (worst of fx, fy, both cameras) %, principal point
    (worst camera) px, baseline %, stereo rotation angle deg, held-out triangulated corners mean 3-D
    error mm (and their RMS board-shape residual mm, which needs no truth)."""

    focal_err_pct: float
    principal_err_px: float
    baseline_err_pct: float
    rotation_err_deg: float
    held_out_3d_error_mm: float
    held_out_board_rms_mm: float


@dataclass
class CalibrationScenarioResult:
    """Top-level figures are the default (pinhole/Brown-Conrady) model's; `models` has every model's."""

    seed: int
    views: int
    views_used: int
    corner_noise_px: float
    corner_error_px: float
    detector_error_px: float
    rms_px: float
    stereo_rms_px: float
    rectified_row_error_mean_px: float
    rectified_row_error_rms_px: float
    bundle_adjustment_s: float
    focal_err_pct: float
    principal_err_px: float
    baseline_err_pct: float
    rotation_err_deg: float
    held_out_3d_error_mm: float
    best_model: str
    models: dict[str, ModelFigures] = field(default_factory=dict)
    opencv: dict[str, float] = field(default_factory=dict)

    def to_json(self) -> dict[str, object]:
        d = asdict(self)
        d["scenario"] = "calibration"
        return d


def sample_poses(rng: np.random.Generator, n: int, rig: StereoRig) -> list[BoardPose]:
    """n board poses at the three DISTANCES_M in turn, tilted up to ±35° and spread over the image, each
    with the whole board (plus a 12 px border) inside both cameras' images."""
    poses: list[BoardPose] = []
    centre = np.array([(BOARD.cols - 1) * BOARD.square / 2, (BOARD.rows - 1) * BOARD.square / 2, 0.0])
    while len(poses) < n:
        z = DISTANCES_M[len(poses) % len(DISTANCES_M)] * rng.uniform(0.95, 1.05)
        ang = np.radians([rng.uniform(-t, t) for t in TILT_DEG])
        R = euler_to_matrix(*ang)
        target = np.array([rng.uniform(-SPREAD[0], SPREAD[0]) * z, rng.uniform(-SPREAD[1], SPREAD[1]) * z, z])
        pose = BoardPose(R, target - R @ centre)
        inside = [_inside(cam.project(pose.corners_rig(BOARD.cols, BOARD.rows, BOARD.square)), cam.size)
                  for cam in (rig.left, rig.right)]
        if all(inside) or (len(poses) % 2 == 1 and MONO_VIEWS and any(inside)):
            poses.append(pose)
    return poses


def _inside(p: F64, size: tuple[int, int], border: float = 12.0) -> bool:
    return bool(np.all((p >= border) & (p <= np.array(size) - 1 - border)))


def render_views(rig: StereoRig, poses: list[BoardPose], rng: np.random.Generator) -> tuple[ViewSet, F64]:
    """Render and detect every pose in both cameras. Returns the ViewSet (detected corners) and the true
    corner projections (2, V, N, 2) px."""
    V, N = len(poses), BOARD.n_corners
    obs, truth = np.full((2, V, N, 2), np.nan), np.zeros((2, V, N, 2))
    seen = np.zeros((2, V), dtype=bool)
    for v, pose in enumerate(poses):
        for c, cam in enumerate((rig.left, rig.right)):
            truth[c, v] = cam.project(pose.corners_rig(BOARD.cols, BOARD.rows, BOARD.square))
            img = render_board(cam, BOARD.cols, BOARD.rows, BOARD.square, pose, noise_sigma=IMAGE_NOISE,
                               rng=rng)
            det = detect_board(img, BOARD)
            if det.corners is not None:
                obs[c, v], seen[c, v] = det.corners, True
    names = [f"sim-{v:02d}" for v in range(V)]
    return ViewSet(obs, seen, BOARD.object_points(), rig.left.size, names), truth


def add_corner_noise(
    views: ViewSet, truth: F64, sigma: float, rng: np.random.Generator
) -> tuple[float, float]:
    """Top the detector's error up to `sigma` px per coordinate; returns (detector, total) RMS per
    coordinate against the truth, px."""
    err = (views.obs - truth)[views.seen]
    det = float(np.sqrt(np.mean(err**2)))
    extra = np.sqrt(max(sigma**2 - det**2, 0.0))
    views.obs[views.seen] += rng.normal(0.0, extra, views.obs[views.seen].shape)
    total = float(np.sqrt(np.mean((views.obs - truth)[views.seen] ** 2)))
    return det, total


def _rotation_angle_deg(Ra: F64, Rb: F64) -> float:
    c = (np.trace(Ra.T @ Rb) - 1.0) / 2.0
    return float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))))


def _pose_figures(rig: StereoRig, true: StereoRig) -> tuple[float, float]:
    b = abs(rig.baseline - true.baseline) / true.baseline * 100.0
    return b, _rotation_angle_deg(rig.R, true.R)


def _held_out(true: StereoRig, held: ViewSet, truth_pts: F64) -> tuple[F64, F64, F64]:
    """Corners (M, 2) of held-out views seen by both cameras and their true left-camera-frame points."""
    both = held.seen[0] & held.seen[1]
    pl, pr = held.obs[0][both].reshape(-1, 2), held.obs[1][both].reshape(-1, 2)
    X = truth_pts[both].reshape(-1, 3)
    Xl = (X - true.left.c) @ true.left.R_rc.T
    return pl, pr, Xl


def _figures_3d(est: F64, Xl: F64) -> tuple[float, float]:
    from calibration.evaluate import board_shape_rms

    err = float(np.mean(np.linalg.norm(est - Xl, axis=1)) * 1000.0)
    n = BOARD.n_corners
    shape = [board_shape_rms(est[i : i + n], BOARD.object_points()) for i in range(0, len(est), n)]
    return err, float(np.mean(shape) * 1000.0)


def _pinhole_figures(cal: StereoCalibration, true: StereoRig, pl: F64, pr: F64, Xl: F64) -> ModelFigures:
    rig = cal.rig
    f_err = max(
        abs(est.K[i, i] - tr.K[i, i]) / tr.K[i, i] * 100.0
        for est, tr in ((rig.left, true.left), (rig.right, true.right)) for i in (0, 1)
    )
    c_err = max(float(np.linalg.norm(est.K[:2, 2] - tr.K[:2, 2]))
                for est, tr in ((rig.left, true.left), (rig.right, true.right)))
    b, rot = _pose_figures(rig, true)
    e3, shape = _figures_3d(triangulate_pinhole(rig, pl, pr), Xl)
    return ModelFigures(float(f_err), c_err, b, rot, e3, shape)


def _polynomial_figures(
    lenses: tuple[PolynomialLens, PolynomialLens], cal: StereoCalibration, true: StereoRig,
    pl: F64, pr: F64, Xl: F64,
) -> ModelFigures:
    from calibration.polynomial import effective_pinhole

    z = float(np.median(Xl[:, 2]))
    f_err, c_err = 0.0, 0.0
    for lens, tr in zip(lenses, (true.left, true.right), strict=True):
        fx, fy, cx, cy = effective_pinhole(lens, z)
        f_err = max(f_err, abs(fx - tr.K[0, 0]) / tr.K[0, 0] * 100, abs(fy - tr.K[1, 1]) / tr.K[1, 1] * 100)
        c_err = max(c_err, float(np.hypot(cx - tr.K[0, 2], cy - tr.K[1, 2])))
    b, rot = _pose_figures(cal.rig, true)  # stage 2 (R, T) is shared by both lens models
    start = triangulate_pinhole(cal.rig, pl, pr)
    est = triangulate_polynomial(lenses, cal.rig.R, cal.rig.T, pl, pr, start)
    e3, shape = _figures_3d(est, Xl)
    return ModelFigures(f_err, c_err, b, rot, e3, shape)


def run_calibration_scenario(
    seed: int = 0, views: int = 30, corner_noise_px: float = 0.1
) -> CalibrationScenarioResult:
    """Render `views` + HELD_OUT board poses of the default simulated rig, calibrate from the first
    `views` with `corner_noise_px` (per coordinate) corner error, and compare with the truth."""
    rng = np.random.default_rng(seed)
    true = default_rig()
    poses = sample_poses(rng, views + HELD_OUT, true)
    allv, truth = render_views(true, poses, rng)
    det_err, total = add_corner_noise(allv, truth, corner_noise_px, rng)
    train = allv.subset(np.arange(len(poses)) < views)
    held = allv.subset(np.arange(len(poses)) >= views)
    truth_pts = np.stack([p.corners_rig(BOARD.cols, BOARD.rows, BOARD.square) for p in poses[views:]])
    cal = calibrate_stereo(train, BOARD)
    pl, pr, Xl = _held_out(true, held, truth_pts)
    models = {"pinhole": _pinhole_figures(cal, true, pl, pr, Xl)}
    if cal.polynomial is not None:
        models["polynomial"] = _polynomial_figures(cal.polynomial, cal, true, pl, pr, Xl)
    best = min(models, key=lambda m: models[m].held_out_3d_error_mm)
    ph = models["pinhole"]
    return CalibrationScenarioResult(
        seed, views, len(cal.names), corner_noise_px, total, det_err, cal.ba.rms, cal.stereo_rms_px,
        cal.rect.row_error_mean_px, cal.rect.row_error_rms_px, cal.ba.seconds, ph.focal_err_pct,
        ph.principal_err_px, ph.baseline_err_pct, ph.rotation_err_deg, ph.held_out_3d_error_mm, best,
        models, opencv_stereo(train).to_json(),
    )
