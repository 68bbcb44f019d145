"""Chessboard target: model points, sub-pixel corner detection and false-detection rejection.

Detection is cv2.findChessboardCorners followed by cv2.cornerSubPix: on the OpenCV test images
(chess1-8) that measured 0.012 px mean error against the reference corners, against 0.15-0.37 px for
cv2.findChessboardCornersSB (with or without CALIB_CB_ACCURACY); see tests/test_calib_board.py.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from calibration.errors import CalibrationError

F64 = NDArray[np.float64]
U8 = NDArray[np.uint8]

# cornerSubPix search half-window (px) and stopping rule; half-window 5 (an 11x11 window) measured best.
SUBPIX_HALF_WINDOW = 5
SUBPIX_CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 40, 1e-3)
# Largest accepted deviation of a corner from the homography of its 2x2-square neighbourhood,
# as a fraction of the local square size (lens distortion over two squares stays far below this).
REGULARITY_TOL = 0.12
# Smallest mean grey-level difference between dark and light squares that decides a board's orientation.
MIN_CELL_CONTRAST = 20.0
# The board sizes a calibration accepts: inner corners a side, and the square's side (in the unit of T,
# metres in tmeye; below 0.1 mm the model points are too close for OpenCV's homography to start from).
MAX_CORNERS = 100
MIN_SQUARE = 1e-4


@dataclass(frozen=True)
class BoardSpec:
    """A chessboard with `cols` x `rows` inner corners and squares of `square` metres (or any unit)."""

    cols: int
    rows: int
    square: float

    @property
    def pattern_size(self) -> tuple[int, int]:
        """(cols, rows), OpenCV's patternSize."""
        return self.cols, self.rows

    @property
    def n_corners(self) -> int:
        return self.cols * self.rows

    def object_points(self) -> F64:
        """Board-frame corner coordinates, shape (rows*cols, 3), row-major, z = 0, in `square` units."""
        j, i = np.meshgrid(np.arange(self.cols), np.arange(self.rows))
        pts = np.stack([j.ravel(), i.ravel(), np.zeros(j.size)], axis=1)
        return pts.astype(np.float64) * self.square

    @staticmethod
    def parse(text: str, square: float) -> BoardSpec:
        """'9x6' (inner corners, columns x rows) and the square size -> BoardSpec; ValueError if malformed."""
        m = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
        if not m:
            raise CalibrationError(f"board size {text!r} is not COLSxROWS (inner corners), e.g. 9x6")
        cols, rows = int(m.group(1)), int(m.group(2))
        if cols < 3 or rows < 3:
            raise CalibrationError(f"board {cols}x{rows} is too small: need at least 3x3 inner corners")
        if cols > MAX_CORNERS or rows > MAX_CORNERS:  # 10^20 columns failed in the database, not here
            raise CalibrationError(f"board {cols}x{rows} is too large: at most {MAX_CORNERS} inner corners a side")
        if not square > 0:
            raise CalibrationError(f"square size must be positive, got {square}")
        if not MIN_SQUARE <= square < math.inf:  # 1e-300 m: OpenCV's homography assertion, not a reason
            raise CalibrationError(f"square size must be at least {MIN_SQUARE:g} and finite, got {square:g}")
        return BoardSpec(cols, rows, float(square))


@dataclass(frozen=True)
class Detection:
    """Outcome of looking for the board in one image: corners (N, 2) px, or None with the reason.
    oriented: the corner order is fixed to the board by its colours (else only to the image)."""

    corners: F64 | None
    reason: str = ""
    oriented: bool = False


def regularity_error(corners: F64, board: BoardSpec) -> float:
    """Worst deviation of any corner from the homography fitted to the four outer corners of each
    2x2-square block around it, as a fraction of the local square size (dimensionless)."""
    g = corners.reshape(board.rows, board.cols, 2)
    worst = 0.0
    ref = np.array([[0, 0], [2, 0], [0, 2], [2, 2]], dtype=np.float64)
    inner = np.array([[1, 0], [0, 1], [1, 1], [2, 1], [1, 2]], dtype=np.float64)
    for i in range(0, board.rows - 2):
        for j in range(0, board.cols - 2):
            blk = g[i : i + 3, j : j + 3]
            dst = np.array([blk[0, 0], blk[0, 2], blk[2, 0], blk[2, 2]])
            H = cv2.getPerspectiveTransform(ref.astype(np.float32), dst.astype(np.float32))
            pred = cv2.perspectiveTransform(inner.reshape(-1, 1, 2), H).reshape(-1, 2)
            got = np.array([blk[0, 1], blk[1, 0], blk[1, 1], blk[1, 2], blk[2, 1]])
            size = 0.5 * np.mean(np.linalg.norm(dst[[1, 2, 3, 3]] - dst[[0, 0, 1, 2]], axis=1))
            worst = max(worst, float(np.max(np.linalg.norm(pred - got, axis=1)) / max(size, 1e-9)))
    return worst


def cell_contrast(gray: U8, corners: F64, board: BoardSpec) -> float:
    """Mean grey level of the squares between the inner corners whose cell index i + j is even, less that
    of the odd ones (grey levels); cell (i, j) lies between corners (i, j) and (i + 1, j + 1), sampled at
    its centre on a lightly blurred image. Negative when cell (0, 0) is a dark square."""
    g = corners.reshape(board.rows, board.cols, 2)
    centres = 0.25 * (g[:-1, :-1] + g[:-1, 1:] + g[1:, :-1] + g[1:, 1:])  # (rows-1, cols-1, 2)
    blur = cv2.GaussianBlur(gray, (5, 5), 0)
    pts = centres.reshape(-1, 1, 2).astype(np.float32)
    vals = cv2.remap(blur, pts[..., 0], pts[..., 1], cv2.INTER_LINEAR).astype(np.float64).ravel()
    i, j = np.meshgrid(np.arange(board.rows - 1), np.arange(board.cols - 1), indexing="ij")
    even = ((i + j) % 2 == 0).ravel()
    return float(vals[even].mean() - vals[~even].mean())


def orient_by_colour(gray: U8, corners: F64, board: BoardSpec) -> F64 | None:
    """Order the corners so that cell (0, 0) is a dark square, fixing the corner order to the board
    itself (OpenCV may return a grid or its 180° turn, and the two cameras of a pair may differ). Only a
    board whose cols + rows is odd changes colour under a 180° turn; None for the others, or when the
    squares' contrast is below MIN_CELL_CONTRAST grey levels."""
    if (board.cols + board.rows) % 2 == 0:
        return None
    c = cell_contrast(gray, corners, board)
    if abs(c) < MIN_CELL_CONTRAST:
        return None
    return corners[::-1].copy() if c > 0 else corners


def canonical_order(corners: F64, board: BoardSpec) -> F64:
    """For a board symmetric under a 180° turn (cols + rows even): the first corner is the one nearer
    the image's top-left. A stereo pair's two views are then aligned by `align_pair`."""
    first, last = corners[0], corners[-1]
    if (last[0] - first[0]) + (last[1] - first[1]) < 0:
        return corners[::-1].copy()
    return corners


def align_pair(left: F64, right: F64) -> F64:
    """The right view's corners in the order of the left's, for a board whose colours cannot tell its
    180° turns apart: the cameras of a rig are nearly parallel, so the first-to-last corner directions
    of one board point the same way in both images (reversed if they point apart)."""
    dl, dr = left[-1] - left[0], right[-1] - right[0]
    return right[::-1].copy() if float(dl @ dr) < 0 else right


def detect_board(gray: U8, board: BoardSpec) -> Detection:
    """Find the board's inner corners with sub-pixel accuracy in a grey uint8 image (H, W).

    Returns Detection(corners (rows*cols, 2) float64 px, row-major) or Detection(None, reason) when no
    board with this corner count is seen or the found grid is irregular (a false detection)."""
    flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
    found, c = cv2.findChessboardCorners(gray, board.pattern_size, flags=flags)
    if not found or c is None or len(c) != board.n_corners:
        return Detection(None, f"no {board.cols}x{board.rows} board found")
    spacing = _min_spacing(c.reshape(-1, 2).astype(np.float64), board)
    half = int(max(2, min(SUBPIX_HALF_WINDOW, np.floor(spacing * 0.45))))
    refined = cv2.cornerSubPix(gray, c.astype(np.float32), (half, half), (-1, -1), SUBPIX_CRITERIA)
    corners = refined.reshape(-1, 2).astype(np.float64)
    err = regularity_error(corners, board)
    if err > REGULARITY_TOL:
        return Detection(None, f"irregular corner grid (deviation {err:.2f} of a square > {REGULARITY_TOL})")
    oriented = orient_by_colour(gray, corners, board)
    if oriented is None:
        return Detection(canonical_order(corners, board), oriented=False)
    return Detection(oriented, oriented=True)


def _min_spacing(corners: F64, board: BoardSpec) -> float:
    """Smallest distance (px) between neighbouring corners of a (rows*cols, 2) grid."""
    g = corners.reshape(board.rows, board.cols, 2)
    dx = np.linalg.norm(np.diff(g, axis=1), axis=2)
    dy = np.linalg.norm(np.diff(g, axis=0), axis=2)
    return float(min(dx.min(), dy.min()))
