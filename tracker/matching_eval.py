"""Point matching on real rectified pairs with known disparity (Middlebury, ../shared/data/stereo-gt):
tracker.point_match.match_point against OpenCV's StereoSGBM at the same textured points, in the same run.

Points: a grid every GRID_STEP px of the left image (im2.png) where the true disparity is known
(disp2.png / scale, 0 = unknown), not occluded (the right view's truth disp6.png at x - d agrees within
1 px), the match window lies inside the image, and the window's grey-level standard deviation is at least
TEXTURE_STD (textured). For each method: the share of those points it answers, and over its answers the
median |d - d_true| (px) and the share of errors above 1 px."""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.point_match import match_point

F64 = NDArray[np.float64]
U8 = NDArray[np.uint8]

GRID_STEP = 4
TEXTURE_STD = 8.0  # grey levels over the 11x11 window
WINDOW = 11
SCALE = {"barn2": 8, "bull": 8, "cones": 4, "poster": 8, "sawtooth": 8, "teddy": 4, "tsukuba": 16, "venus": 8}


@dataclass(frozen=True)
class MethodFigures:
    """answered: share of the points given a disparity; median_err_px and over_1px over the answers."""

    answered: float
    median_err_px: float
    over_1px: float
    seconds: float


@dataclass(frozen=True)
class PairFigures:
    name: str
    points: int
    max_disparity: int
    match_point: MethodFigures
    sgbm: MethodFigures

    def to_json(self) -> dict[str, object]:
        return asdict(self)

    @property
    def beats_sgbm(self) -> bool:
        m, s = self.match_point, self.sgbm
        return m.median_err_px < s.median_err_px and m.over_1px < s.over_1px and m.answered >= 0.85


@dataclass(frozen=True)
class Pair:
    name: str
    left: U8
    right: U8
    truth: F64  # (H, W) left-view disparity px, 0 unknown
    truth_right: F64


def read_pair(folder: Path) -> Pair:
    """im2/im6 as grey images and disp2/disp6 divided by the data set's scale factor."""
    name = folder.name
    scale = SCALE.get(name, 8)
    read = [cv2.imread(str(folder / f), cv2.IMREAD_GRAYSCALE) for f in ("im2.png", "im6.png", "disp2.png",
                                                                         "disp6.png")]
    if any(a is None for a in read):
        raise ValueError(f"{folder}: needs im2.png, im6.png, disp2.png and disp6.png")
    a = [np.asarray(x, np.uint8) for x in read]
    return Pair(name, a[0], a[1], a[2].astype(np.float64) / scale, a[3].astype(np.float64) / scale)


def textured_points(p: Pair, dmax: int) -> tuple[NDArray[np.int_], NDArray[np.int_]]:
    """(ys, xs) of the evaluated points (see the module's docstring)."""
    H, W = p.left.shape
    h = WINDOW // 2
    f = p.left.astype(np.float64)
    mean = cv2.boxFilter(f, -1, (WINDOW, WINDOW))
    std = np.sqrt(np.maximum(cv2.boxFilter(f * f, -1, (WINDOW, WINDOW)) - mean * mean, 0.0))
    ys, xs = np.mgrid[h + 1 : H - h - 2 : GRID_STEP, h + dmax + 4 : W - h - 4 : GRID_STEP]
    ys, xs = ys.ravel(), xs.ravel()
    d = p.truth[ys, xs]
    xr = np.clip(np.round(xs - d).astype(int), 0, W - 1)
    ok = (d > 0) & (std[ys, xs] >= TEXTURE_STD) & (np.abs(p.truth_right[ys, xr] - d) <= 1.0)
    return ys[ok], xs[ok]


def _figures(est: F64, truth: F64, seconds: float) -> MethodFigures:
    ans = np.isfinite(est)
    err = np.abs(est[ans] - truth[ans])
    return MethodFigures(float(ans.mean()), float(np.median(err)) if err.size else float("nan"),
                         float((err > 1.0).mean()) if err.size else float("nan"), seconds)


def sgbm_disparity(left: U8, right: U8, dmax: int) -> F64:
    """OpenCV StereoSGBM (block 5, P1 = 8·25, P2 = 32·25, uniqueness 10, speckle filter, full 8-path
    mode): the disparity map (H, W) px, NaN where SGBM gives none."""
    nd = 16 * int(np.ceil((dmax + 1) / 16))
    sgbm = cv2.StereoSGBM.create(minDisparity=0, numDisparities=nd, blockSize=5, P1=8 * 25, P2=32 * 25,
                                 disp12MaxDiff=1, uniquenessRatio=10, speckleWindowSize=100, speckleRange=2,
                                 mode=cv2.STEREO_SGBM_MODE_HH)
    d = np.asarray(sgbm.compute(left, right)).astype(np.float64) / 16.0
    return np.where(d >= 0, d, np.nan)


def evaluate_pair(p: Pair) -> PairFigures:
    dmax = int(np.ceil(p.truth.max())) + 4
    ys, xs = textured_points(p, dmax)
    truth = p.truth[ys, xs]
    t0 = time.perf_counter()
    est_m = np.array([np.nan if (d := match_point(p.left, p.right, float(x), float(y), dmax)) is None else d
                      for y, x in zip(ys, xs, strict=True)])
    t1 = time.perf_counter()
    est_s = sgbm_disparity(p.left, p.right, dmax)[ys, xs]
    t2 = time.perf_counter()
    return PairFigures(p.name, int(ys.size), dmax, _figures(est_m, truth, t1 - t0), _figures(est_s, truth, t2 - t1))


def evaluate_matching(root: Path) -> list[PairFigures]:
    """Every data set folder under `root` (each with im2/im6/disp2/disp6)."""
    folders = sorted(f for f in root.iterdir() if (f / "im2.png").exists())
    if not folders:
        raise ValueError(f"no stereo pairs (NAME/im2.png, im6.png, disp2.png, disp6.png) under {root}")
    return [evaluate_pair(read_pair(f)) for f in folders]
