"""Exact rendering of chessboard views for the simulated rig (calibration ground truth, issue 3).

Every pixel is rendered from the true camera: each of its ss x ss sub-samples is turned into a ray
through the lens model (Camera.undistort_pixels, which undoes the Brown-Conrady distortion, evaluated
exactly on the pixel grid and interpolated between pixels; only the board's bounding box), the ray is
intersected with the board plane, and the sub-sample takes the colour of the square it lands on; the
pixel is their mean (anti-aliasing), so the rendered corners are where the true projection puts them to
a small fraction of a pixel. The board is a plate of (cols+1) x (rows+1) squares with a white margin,
in front of a uniform grey background.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from tracker.geometry import Camera

F64 = NDArray[np.float64]
F32 = NDArray[np.float32]
U8 = NDArray[np.uint8]

BLACK, WHITE, BACKGROUND = 25.0, 230.0, 120.0
_GRID_CACHE: dict[tuple[bytes, ...], F64] = {}


@dataclass(frozen=True)
class BoardPose:
    """Board placement in the rig frame: X_rig = R @ X_board + t. The board frame has its origin at the
    first inner corner, x along a row of inner corners, y down the columns, z into the board; metres."""

    R: F64
    t: F64

    def corners_rig(self, cols: int, rows: int, square: float) -> F64:
        """Inner corners in the rig frame, shape (rows*cols, 3), row-major (same order as detection)."""
        j, i = np.meshgrid(np.arange(cols), np.arange(rows))
        pts = np.stack([j.ravel() * square, i.ravel() * square, np.zeros(j.size)], axis=1)
        out: F64 = pts @ self.R.T + self.t
        return out


def _pixel_grid(cam: Camera) -> F64:
    """Undistorted normalised coordinates (x, y) of every integer pixel position from -1 to w (and -1 to
    h), shape (h + 2, w + 2, 2), float64; cached per camera (2.5 MB at 640 x 480, ~0.1 s)."""
    key = (cam.K.tobytes(), cam.dist.tobytes(), repr(cam.size).encode())
    if key not in _GRID_CACHE:
        w, h = cam.size
        uu, vv = np.meshgrid(np.arange(-1.0, w + 1.0), np.arange(-1.0, h + 1.0))
        xn, yn = cam.undistort_pixels(uu, vv, iterations=20)
        _GRID_CACHE[key] = np.stack([xn, yn], axis=-1)
    return _GRID_CACHE[key]


def _subsample_xy(cam: Camera, ss: int, box: tuple[int, int, int, int]) -> tuple[F32, F32]:
    """Undistorted normalised camera coordinates (x, y) of the ss x ss sub-samples of the pixels in
    box = (x0, y0, x1, y1), each shaped (y1 - y0, ss, x1 - x0, ss); pixel centres are at integer
    coordinates (OpenCV convention). A sub-sample's coordinates are bilinearly interpolated from the
    exact per-pixel grid (the weights are the same for every pixel, so this is four shifted slices per
    sub-sample offset); the lens map is smooth, so the error is below 1e-4 px."""
    x0, y0, x1, y1 = box
    grid = _pixel_grid(cam)
    offs = (np.arange(ss) + 0.5) / ss - 0.5
    out = np.empty((2, y1 - y0, ss, x1 - x0, ss), dtype=np.float32)
    for j, oy in enumerate(offs):
        r0, av = (y0, 1.0 + oy) if oy < 0 else (y0 + 1, oy)  # grid row index of pixel row y is y + 1
        for i, ox in enumerate(offs):
            c0, au = (x0, 1.0 + ox) if ox < 0 else (x0 + 1, ox)
            g = grid[r0 : r0 + (y1 - y0) + 1, c0 : c0 + (x1 - x0) + 1]
            top = (1.0 - au) * g[:-1, :-1] + au * g[:-1, 1:]
            bot = (1.0 - au) * g[1:, :-1] + au * g[1:, 1:]
            out[:, :, j, :, i] = np.moveaxis((1.0 - av) * top + av * bot, -1, 0)
    return out[0], out[1]


def _bbox(cam: Camera, pose: BoardPose, lo: F64, hi: F64) -> tuple[int, int, int, int] | None:
    """Pixel bounding box (x0, y0, x1, y1) of the board plate's outline, or None if it is behind."""
    s = np.linspace(0.0, 1.0, 25)
    span = hi - lo
    xs = np.r_[lo[0] + s * span[0], np.full(25, hi[0]), hi[0] - s * span[0], np.full(25, lo[0])]
    ys = np.r_[np.full(25, lo[1]), lo[1] + s * span[1], np.full(25, hi[1]), hi[1] - s * span[1]]
    X = np.stack([xs, ys, np.zeros_like(xs)], axis=1) @ pose.R.T + pose.t
    Xc = (X - cam.c) @ cam.R_rc.T
    if np.any(Xc[:, 2] <= 1e-6):
        return 0, 0, cam.size[0], cam.size[1]
    p = cam.project(X)
    w, h = cam.size
    x0, y0 = int(np.clip(np.floor(p[:, 0].min()) - 2, 0, w)), int(np.clip(np.floor(p[:, 1].min()) - 2, 0, h))
    x1, y1 = int(np.clip(np.ceil(p[:, 0].max()) + 3, 0, w)), int(np.clip(np.ceil(p[:, 1].max()) + 3, 0, h))
    return None if x1 <= x0 or y1 <= y0 else (x0, y0, x1, y1)


def render_board(
    cam: Camera,
    cols: int,
    rows: int,
    square: float,
    pose: BoardPose,
    supersample: int = 4,
    margin_squares: float = 1.0,
    noise_sigma: float = 0.0,
    rng: np.random.Generator | None = None,
) -> U8:
    """Grey image (H, W) uint8 of a board with `cols` x `rows` inner corners and `square` m squares seen
    by `cam`; `margin_squares` of white border around the squares; optional Gaussian noise (grey levels)."""
    w, h = cam.size
    img = np.full((h, w), BACKGROUND)
    m = margin_squares * square
    lo = np.array([-square - m, -square - m])
    hi = np.array([cols * square + m, rows * square + m])
    box = _bbox(cam, pose, lo, hi)
    if box is not None:
        x0, y0, x1, y1 = box
        x, y = _subsample_xy(cam, supersample, box)
        img[y0:y1, x0:x1] = _shade(x, y, cam, pose, square, lo, hi).mean(axis=(1, 3))
    if noise_sigma > 0:
        gen = rng if rng is not None else np.random.default_rng()
        img = img + gen.normal(0.0, noise_sigma, img.shape)
    out: U8 = np.clip(np.rint(img), 0, 255).astype(np.uint8)
    return out


def _shade(x: F32, y: F32, cam: Camera, pose: BoardPose, square: float, lo: F64, hi: F64) -> F32:
    """Intensity of each sub-sample with camera-frame ray (x, y, 1): intersect with the board plane
    z_board = 0 (all vectors taken into the camera frame)."""
    n = (cam.R_rc @ pose.R[:, 2]).astype(np.float32)  # plane normal
    ax = (cam.R_rc @ pose.R[:, 0]).astype(np.float32)  # board x and y axes
    ay = (cam.R_rc @ pose.R[:, 1]).astype(np.float32)
    o = (cam.R_rc @ (cam.c - pose.t)).astype(np.float32)  # lens centre relative to the board origin
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = -float(o @ n) / (x * n[0] + y * n[1] + n[2])
    bx = float(o @ ax) + lam * (x * ax[0] + y * ax[1] + ax[2])
    by = float(o @ ay) + lam * (x * ay[0] + y * ay[1] + ay[2])
    hit = (lam > 0) & (bx >= lo[0]) & (bx <= hi[0]) & (by >= lo[1]) & (by <= hi[1])
    kx, ky = np.floor(bx / square), np.floor(by / square)
    margin = -square - lo[0]
    on_squares = (bx >= -square) & (by >= -square) & (bx < hi[0] - margin) & (by < hi[1] - margin)
    black = on_squares & ((kx + ky) % 2 == 0)
    val = np.where(black, np.float32(BLACK), np.float32(WHITE))
    out: F32 = np.where(hit, val, np.float32(BACKGROUND)).astype(np.float32)
    return out
