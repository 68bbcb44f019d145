"""Exact rendering of chessboard views for the simulated rig (calibration ground truth, issue 3).

Every pixel is rendered from the true camera: each of its ss x ss sub-samples is turned into a ray
through the lens model (Camera.rays_rig, which undoes the Brown-Conrady distortion), the ray is
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
_RAY_CACHE: dict[tuple[bytes, ...], F32] = {}


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


def _subsample_rays(cam: Camera, ss: int) -> F32:
    """Unit rays in the rig frame for ss x ss sub-samples of every pixel, shape (H, ss, W, ss, 3);
    pixel centres are at integer coordinates (OpenCV convention). Cached per camera."""
    key = (cam.K.tobytes(), cam.dist.tobytes(), cam.R_rc.tobytes(), cam.c.tobytes(),
           repr((cam.size, ss)).encode())
    if key not in _RAY_CACHE:
        w, h = cam.size
        offs = (np.arange(ss) + 0.5) / ss - 0.5
        u = (np.arange(w)[:, None] + offs[None, :]).ravel()
        v = (np.arange(h)[:, None] + offs[None, :]).ravel()
        uu, vv = np.meshgrid(u, v)
        rays = cam.rays_rig(uu, vv).astype(np.float32)
        _RAY_CACHE[key] = rays.reshape(h, ss, w, ss, 3)
    return _RAY_CACHE[key]


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
        rays = _subsample_rays(cam, supersample)[y0:y1, :, x0:x1]
        img[y0:y1, x0:x1] = _shade(rays, cam, pose, square, lo, hi).mean(axis=(1, 3))
    if noise_sigma > 0:
        gen = rng if rng is not None else np.random.default_rng()
        img = img + gen.normal(0.0, noise_sigma, img.shape)
    out: U8 = np.clip(np.rint(img), 0, 255).astype(np.uint8)
    return out


def _shade(rays: F32, cam: Camera, pose: BoardPose, square: float, lo: F64, hi: F64) -> F32:
    """Intensity of each sub-sample ray (..., 3): intersect with the board plane z_board = 0."""
    n = pose.R[:, 2].astype(np.float32)  # plane normal in the rig frame
    origin = (cam.c - pose.t).astype(np.float32)  # ray origin relative to the board origin
    denom = rays @ n
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = -(origin @ n) / denom
    P = origin + lam[..., None] * rays  # rig-frame offsets from the board origin
    bx = P @ pose.R[:, 0].astype(np.float32)
    by = P @ pose.R[:, 1].astype(np.float32)
    hit = (lam > 0) & (bx >= lo[0]) & (bx <= hi[0]) & (by >= lo[1]) & (by <= hi[1])
    kx, ky = np.floor(bx / square), np.floor(by / square)
    margin = -square - lo[0]
    on_squares = (bx >= -square) & (by >= -square) & (bx < hi[0] - margin) & (by < hi[1] - margin)
    black = on_squares & ((kx + ky) % 2 == 0)
    val = np.where(black, BLACK, WHITE)
    out: F32 = np.where(hit, val, BACKGROUND).astype(np.float32)
    return out
