"""Readers for the OpenCV calibration test data (../shared/data/chessboards, see its README)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from calibration.errors import CalibrationError

F64 = NDArray[np.float64]


@dataclass(frozen=True)
class ReferenceCorners:
    """Reference corners of one image: `corners` (rows*cols, 2) px, pattern (cols, rows), is_found."""

    corners: F64
    pattern_size: tuple[int, int]
    is_found: bool


def read_reference_corners(path: str | Path) -> ReferenceCorners:
    """Read chess_corners*.dat (OpenCV FileStorage YAML: `corners` rows x cols of 2-channel float)."""
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    if not fs.isOpened():
        raise CalibrationError(f"cannot read reference corners {path}")
    try:
        m = fs.getNode("corners").mat()
        found = bool(int(fs.getNode("isFound").real()))
    finally:
        fs.release()
    if m is None:
        raise CalibrationError(f"{path} has no `corners` matrix")
    rows, cols = m.shape[:2]
    return ReferenceCorners(np.asarray(m, dtype=np.float64).reshape(-1, 2), (cols, rows), found)


@dataclass(frozen=True)
class BouguetData:
    """calib1.dat: per-view board points (V, N, 3) cm and image points (V, N, 2) px, plus the
    reference solution of Bouguet's toolbox: fc (2,), cc (2,), kc (4,) = k1 k2 p1 p2."""

    image_size: tuple[int, int]
    board_size: tuple[int, int]
    object_points: F64
    image_points: F64
    fc: F64
    cc: F64
    kc: F64


def read_bouguet(path: str | Path) -> BouguetData:
    """Parse calib1.dat: 'W H', 'a b' (board), 'V' (views), then V blocks of N lines 'X Y Z', then V blocks
    of N lines 'u v', then the reference fc (2), cc (2), kc (4); the rest (rotations, translations, the
    toolbox log) is ignored. N = a*b."""
    lines = Path(path).read_text().splitlines()
    nums: list[list[float]] = []
    for line in lines:
        parts = line.split()
        if not parts:
            continue
        try:
            nums.append([float(p) for p in parts])
        except ValueError:
            break  # the toolbox's text log starts here
    w, h = (int(x) for x in nums[0])
    a, b = (int(x) for x in nums[1])
    views, n = int(nums[2][0]), a * b
    pos = 3
    obj = np.array(nums[pos : pos + views * n], dtype=np.float64)
    pos += views * n
    img = np.array(nums[pos : pos + views * n], dtype=np.float64)
    pos += views * n
    if obj.shape != (views * n, 3) or img.shape != (views * n, 2):
        raise CalibrationError(f"{path}: unexpected layout (points {obj.shape}, image points {img.shape})")
    fc, cc = np.array(nums[pos]), np.array(nums[pos + 1])
    kc = np.array(nums[pos + 2])
    return BouguetData((w, h), (a, b), obj.reshape(views, n, 3), img.reshape(views, n, 2), fc, cc, kc)
