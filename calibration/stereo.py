"""Stereo calibration pipeline: start values, joint bundle adjustment (§5), outlier views, rig, figures."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from calibration.board import BoardSpec
from calibration.bundle import BAInput, BAResult, bundle_adjust, intr_matrices, rodrigues
from calibration.errors import TooFewViewsError
from calibration.evaluate import Rectification, coverage, rectify
from calibration.initial import default_fixed, init_stereo
from calibration.polynomial import PolynomialLens, fit_polynomial
from tracker.geometry import Camera, StereoRig

F64 = NDArray[np.float64]
B = NDArray[np.bool_]

MIN_VIEWS = 4  # stereo pairs showing the whole board in both cameras
OUTLIER_FACTOR = 4.0  # a view is an outlier if its RMS exceeds this many times the median ...
OUTLIER_FLOOR_PX = 0.3  # ... and this absolute floor


@dataclass(frozen=True)
class Skip:
    """A view left out of the calibration: its name and why."""

    name: str
    reason: str


@dataclass
class ViewSet:
    """Detected corners of V stereo views: obs (2, V, N, 2) px (NaN where not seen), seen (2, V),
    obj (N, 3) board points; names[v] names the view; skipped lists images with no usable board."""

    obs: F64
    seen: B
    obj: F64
    size: tuple[int, int]
    names: list[str]
    skipped: list[Skip] = field(default_factory=list)

    def subset(self, keep: B) -> ViewSet:
        names = [n for n, k in zip(self.names, keep, strict=True) if k]
        return ViewSet(self.obs[:, keep], self.seen[:, keep], self.obj, self.size, names, list(self.skipped))


@dataclass
class StereoCalibration:
    """Result of calibrate_stereo. ba: final adjustment over `names` views; rig: cameras for the tracker
    (Brown-Conrady); rect: rectification and row error; coverage (left, right) of the image area 0-1;
    polynomial: the eq. (3)-(4) lenses fitted on the same views (None if not enough distances);
    observed (2, V, N, 2): the corners the adjustment used (NaN where unseen)."""

    board: BoardSpec
    size: tuple[int, int]
    ba: BAResult
    names: list[str]
    rejected: list[Skip]
    skipped: list[Skip]
    rig: StereoRig
    rect: Rectification
    coverage: tuple[float, float]
    stereo_rms_px: float
    polynomial: tuple[PolynomialLens, PolynomialLens] | None
    observed: F64
    polynomial_error: str = ""


def check_enough(views: ViewSet) -> None:
    """Raise TooFewViewsError unless MIN_VIEWS stereo pairs show the board in both cameras."""
    pairs = int(np.sum(views.seen[0] & views.seen[1]))
    if pairs < MIN_VIEWS:
        raise TooFewViewsError(
            f"too few usable views: {pairs} stereo pair(s) show the board in both cameras, "
            f"need at least {MIN_VIEWS}"
        )


def _reject_outliers(ba: BAResult, names: list[str]) -> tuple[B, list[Skip]]:
    """Views whose RMS (either camera) exceeds max(OUTLIER_FACTOR x median, OUTLIER_FLOOR_PX)."""
    vr = ba.view_rms
    thr = max(OUTLIER_FLOOR_PX, OUTLIER_FACTOR * float(np.nanmedian(vr)))
    worst = np.nanmax(vr, axis=0)
    bad = worst > thr
    skips = [
        Skip(names[v], f"reprojection RMS {worst[v]:.2f} px > {thr:.2f} px (outlier view)")
        for v in np.flatnonzero(bad)
    ]
    return ~bad, skips


def _adjust(views: ViewSet, fixed: B, loss: str, start: BAResult | None) -> BAResult:
    obj = np.broadcast_to(views.obj, (views.obs.shape[1], *views.obj.shape)).copy()
    obs = np.nan_to_num(views.obs)
    if start is None:
        return bundle_adjust(init_stereo(obj, obs, views.seen, views.size, fixed, loss))
    inp = BAInput(obj, obs, views.seen, start.intr, start.poses, start.R, start.T, fixed, loss)
    return bundle_adjust(inp)


def calibrate_stereo(
    views: ViewSet,
    board: BoardSpec,
    fix_k3: bool = False,
    loss: str = "huber",
    progress: Callable[[str], None] | None = None,
) -> StereoCalibration:
    """Calibrate both cameras and their relative pose from detected views (see ViewSet); drop outlier
    views once and re-adjust; build the rig, rectification, coverage and the polynomial lenses."""
    say = progress or (lambda _msg: None)
    check_enough(views)
    fixed = default_fixed(fix_k3)
    say(f"bundle adjustment over {views.obs.shape[1]} views ...")
    ba = _adjust(views, fixed, loss, None)
    keep, rejected = _reject_outliers(ba, views.names)
    if rejected:
        say(f"dropping {len(rejected)} outlier view(s), adjusting again ...")
        views = views.subset(keep)
        check_enough(views)
        start = BAResult(ba.intr, ba.poses[keep], ba.R, ba.T, ba.euler, ba.residuals, ba.std_intr,
                         ba.std_euler, ba.std_T, 0.0, 0, ba.recentred)
        ba = _adjust(views, fixed, loss, start)
    say(f"RMS reprojection error {ba.rms:.3f} px ({ba.seconds:.2f} s)")
    return _finish(views, board, ba, rejected)


def make_rig(ba: BAResult, size: tuple[int, int]) -> StereoRig:
    """The tracker's cameras from the adjusted intrinsics and x_r = R x_l + T (origin between lenses)."""
    (Kl, dl), (Kr, dr) = intr_matrices(ba.intr[0]), intr_matrices(ba.intr[1])
    return StereoRig.from_extrinsics(Camera(Kl, dl, size), Camera(Kr, dr, size), ba.R, ba.T)


def camera_points(ba: BAResult, obj: F64, cam: int) -> F64:
    """Board corners (V, N, 3) in camera `cam`'s frame from the adjusted poses (eq. 5)."""
    Xl = np.einsum("vij,nj->vni", rodrigues(ba.poses[:, :3]), obj) + ba.poses[:, None, 3:]
    out: F64 = Xl if cam == 0 else Xl @ ba.R.T + ba.T
    return out


def fit_polynomials(views: ViewSet, ba: BAResult) -> tuple[PolynomialLens, PolynomialLens]:
    """Eq. (3)-(4) for each camera from the corners it saw and their adjusted camera-frame positions."""
    lenses = []
    for c in range(2):
        X = camera_points(ba, views.obj, c)[views.seen[c]].reshape(-1, 3)
        pix = views.obs[c][views.seen[c]].reshape(-1, 2)
        lenses.append(fit_polynomial(pix, X, float(ba.intr[c, :2].mean()), views.size))
    return lenses[0], lenses[1]


def _finish(views: ViewSet, board: BoardSpec, ba: BAResult, rejected: list[Skip]) -> StereoCalibration:
    rig = make_rig(ba, views.size)
    both = views.seen[0] & views.seen[1]
    pl, pr = views.obs[0][both].reshape(-1, 2), views.obs[1][both].reshape(-1, 2)
    rect = rectify(rig, pl, pr)
    cov = tuple(coverage(list(views.obs[c][views.seen[c]]), board.pattern_size, views.size) for c in range(2))
    stereo_rms = float(np.sqrt(np.mean(np.sum(ba.residuals[:, both] ** 2, axis=-1))))
    try:
        poly: tuple[PolynomialLens, PolynomialLens] | None = fit_polynomials(views, ba)
        poly_err = ""
    except ValueError as exc:
        poly, poly_err = None, str(exc)
    return StereoCalibration(
        board, views.size, ba, list(views.names), rejected, list(views.skipped), rig, rect,
        (cov[0], cov[1]), stereo_rms, poly, views.obs, poly_err,
    )
