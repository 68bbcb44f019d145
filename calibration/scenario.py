"""Calibration against simulated truth: render board views of tracker.sim.rig.default_rig(), detect,
calibrate, and compare with the true cameras (used by `tmeye eval --scenario calibration`).

The calibration procedure (procedure_poses): a 17x12 inner-corner board of 25 mm squares (an A2 print),
VIEWS poses: two in three are stereo views with the whole board in both images at three distances
(STEREO_DISTANCES_M, as the paper's §4 and eq. 4 need), one in three a close view (MONO_DISTANCES_M)
filling one camera's image, anywhere in it including the corners, that the other camera sees only in
part; every board is tilted 20-45° about a random in-plane axis. The joint adjustment shares the board
poses between the cameras, so the single-camera views pin down each camera's principal point, which
the stereo rotation otherwise trades against (a principal point shift of Δ px looks like a rotation of
Δ/f rad).

Corner noise: the views are rendered exactly (tracker.sim.boards, 4x4 anti-aliasing, 1 grey level of
image noise) and the corners detected; the detector's own error against the true projections is
measured, and Gaussian noise is added to the detected corners so that the total corner error is
`corner_noise_px` RMS as a 2-D distance (OpenCV's RMS convention; per coordinate σ/√2, topped up from
the detector's own error); the measured total is reported as corner_error_px."""

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
# The scenario's calibration procedure (procedure_poses); BOARD and sample_poses are the simpler 9x6
# stereo-only views the CLI tests render.
PROC_BOARD = BoardSpec(17, 12, 0.025)
VIEWS = 60
STEREO_DISTANCES_M = (0.65, 0.9, 1.2)
MONO_DISTANCES_M = (0.45, 0.6)
MONO_EVERY = 3  # every third view fills one camera's image (seen whole by that camera only)
TILT_RANGE_DEG = (20.0, 45.0)  # board tilt about a random in-plane axis
ROLL_DEG = 20.0  # and turned in its plane by up to this


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


def _axis_rotation(axis: F64, angle: float) -> F64:
    k = axis / np.linalg.norm(axis)
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    out: F64 = np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * (K @ K)
    return out


def procedure_poses(
    rng: np.random.Generator, n: int, rig: StereoRig, mono_every: int = MONO_EVERY,
    board: BoardSpec = PROC_BOARD,
) -> list[BoardPose]:
    """n board poses of the calibration procedure (module docstring): view k is a close single-camera
    view when k % mono_every == mono_every - 1 (never when mono_every is 0), else a stereo view at
    STEREO_DISTANCES_M[k % 3]. The board's centre is aimed at a uniformly drawn pixel of one camera; a
    pose is kept when the whole board (plus a 12 px border) is inside the camera(s) it is meant for."""
    cams = (rig.left, rig.right)
    centre = np.array([(board.cols - 1) * board.square / 2, (board.rows - 1) * board.square / 2, 0.0])
    poses: list[BoardPose] = []
    while len(poses) < n:
        k = len(poses)
        mono = mono_every > 0 and k % mono_every == mono_every - 1
        dists = MONO_DISTANCES_M if mono else STEREO_DISTANCES_M
        z = dists[(k // mono_every if mono else k) % len(dists)] * rng.uniform(0.95, 1.05)
        c = int(rng.integers(2))
        w, h = cams[c].size
        d = cams[c].rays_rig(np.array([rng.uniform(0, w)]), np.array([rng.uniform(0, h)]))[0]
        a = rng.uniform(0.0, 2.0 * np.pi)
        R = _axis_rotation(np.array([np.cos(a), np.sin(a), 0.0]), np.radians(rng.uniform(*TILT_RANGE_DEG)))
        R = R @ euler_to_matrix(0.0, 0.0, np.radians(rng.uniform(-ROLL_DEG, ROLL_DEG)))
        pose = BoardPose(R, cams[c].c + d / d[2] * z - R @ centre)
        X = pose.corners_rig(board.cols, board.rows, board.square)
        inside = [_inside(cam.project(X), cam.size) for cam in cams]
        if (mono and inside[c] and not inside[1 - c]) or (not mono and all(inside)):
            poses.append(pose)
    return poses


def render_views(
    rig: StereoRig, poses: list[BoardPose], rng: np.random.Generator, board: BoardSpec = BOARD
) -> tuple[ViewSet, F64]:
    """Render and detect every pose in each camera whose image holds the whole board (a partly seen
    board is never detected, so those images are not rendered). Returns the ViewSet (detected corners)
    and the true corner projections (2, V, N, 2) px."""
    V, N = len(poses), board.n_corners
    obs, truth = np.full((2, V, N, 2), np.nan), np.zeros((2, V, N, 2))
    seen = np.zeros((2, V), dtype=bool)
    for v, pose in enumerate(poses):
        for c, cam in enumerate((rig.left, rig.right)):
            truth[c, v] = cam.project(pose.corners_rig(board.cols, board.rows, board.square))
            if not _inside(truth[c, v], cam.size, 0.0):
                continue
            img = render_board(cam, board.cols, board.rows, board.square, pose, noise_sigma=IMAGE_NOISE,
                               rng=rng)
            det = detect_board(img, board)
            if det.corners is not None:
                obs[c, v], seen[c, v] = det.corners, True
    names = [f"sim-{v:02d}" for v in range(V)]
    return ViewSet(obs, seen, board.object_points(), rig.left.size, names), truth


def add_corner_noise(
    views: ViewSet, truth: F64, sigma: float, rng: np.random.Generator
) -> tuple[float, float]:
    """Top the detector's error up to a total corner error of `sigma` px RMS as a 2-D distance (per
    coordinate sigma/√2); returns (detector, total) 2-D RMS corner errors against the truth, px."""

    def rms2d() -> float:
        return float(np.sqrt(np.mean(np.sum((views.obs - truth)[views.seen] ** 2, axis=-1))))

    det = rms2d()
    extra = np.sqrt(max(sigma**2 - det**2, 0.0) / 2.0)
    views.obs[views.seen] += rng.normal(0.0, extra, views.obs[views.seen].shape)
    return det, rms2d()


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
    n = PROC_BOARD.n_corners
    shape = [board_shape_rms(est[i : i + n], PROC_BOARD.object_points()) for i in range(0, len(est), n)]
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
    seed: int = 0, views: int = VIEWS, corner_noise_px: float = 0.1
) -> CalibrationScenarioResult:
    """Render `views` poses of the calibration procedure (procedure_poses) and HELD_OUT stereo views of
    the default simulated rig, calibrate from the first `views` with `corner_noise_px` (2-D RMS) corner
    error, and compare with the truth."""
    rng = np.random.default_rng(seed)
    true = default_rig()
    poses = procedure_poses(rng, views, true) + procedure_poses(rng, HELD_OUT, true, mono_every=0)
    allv, truth = render_views(true, poses, rng, PROC_BOARD)
    det_err, total = add_corner_noise(allv, truth, corner_noise_px, rng)
    train = allv.subset(np.arange(len(poses)) < views)
    held = allv.subset(np.arange(len(poses)) >= views)
    b = PROC_BOARD
    truth_pts = np.stack([p.corners_rig(b.cols, b.rows, b.square) for p in poses[views:]])
    cal = calibrate_stereo(train, PROC_BOARD)
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
