"""Board detection on the OpenCV test images and Bouguet's calib1.dat reference (real data)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from calib_helpers import chess_dir

from calibration.board import BoardSpec, detect_board, regularity_error
from calibration.datasets import read_bouguet, read_reference_corners
from calibration.initial import calibrate_mono, default_fixed


def _errors() -> list[float]:
    d = chess_dir()
    errs = []
    for i in range(1, 9):
        ref = read_reference_corners(d / f"chess_corners{i}.dat")
        assert ref.is_found
        img = cv2.imread(str(d / f"chess{i}.png"), cv2.IMREAD_GRAYSCALE)
        det = detect_board(img, BoardSpec(*ref.pattern_size, 1.0))
        assert det.corners is not None, det.reason
        c = det.corners
        errs.extend(
            min((np.linalg.norm(c - ref.corners, axis=1), np.linalg.norm(c[::-1] - ref.corners, axis=1)),
                key=lambda e: float(e.mean()))
        )
    return errs


def test_corner_error_against_reference_is_below_003_px() -> None:
    errs = np.array(_errors())
    assert errs.mean() <= 0.03, f"mean corner error {errs.mean():.4f} px"
    assert errs.max() < 0.3


def test_wrong_corner_count_is_not_detected() -> None:
    d = chess_dir()
    img = cv2.imread(str(d / "chess1.png"), cv2.IMREAD_GRAYSCALE)
    for cols, rows in ((6, 7), (5, 8), (4, 7)):
        det = detect_board(img, BoardSpec(cols, rows, 1.0))
        assert det.corners is None
        assert f"{cols}x{rows}" in det.reason


def test_irregular_grid_is_rejected() -> None:
    board = BoardSpec(5, 7, 1.0)
    j, i = np.meshgrid(np.arange(5), np.arange(7))
    good = np.stack([100 + 30.0 * j.ravel(), 80 + 30.0 * i.ravel()], axis=1)
    assert regularity_error(good, board) < 1e-6
    bad = good.copy()
    bad[30:35, 1] += 14.0  # the last row found half a square off the board
    assert regularity_error(bad, board) > 0.12
    blank = np.full((480, 640), 255, np.uint8)
    assert detect_board(blank, board).corners is None


def test_calib1_bundle_adjustment_matches_bouguet_within_005_percent() -> None:
    bd = read_bouguet(chess_dir() / "calib1.dat")
    assert bd.object_points.shape == (7, 35, 3) and bd.image_points.shape == (7, 35, 2)
    res = calibrate_mono(bd.object_points, bd.image_points, bd.image_size, default_fixed(fix_k3=True))
    fx, fy, cx, cy = res.intr[0, :4]
    ref = np.r_[bd.fc, bd.cc]
    rel = np.abs(np.r_[fx, fy, cx, cy] - ref) / ref
    assert np.all(rel < 5e-4), f"fc/cc {fx:.3f} {fy:.3f} {cx:.3f} {cy:.3f} vs {ref}"
    np.testing.assert_allclose(res.intr[0, 4:8], bd.kc, atol=2e-3)
    assert res.rms == pytest.approx(0.1389, abs=2e-3)
