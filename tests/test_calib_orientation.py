"""The board's corner order follows the board, not the image (issue 12 item 6): two cameras of a pair
number the same physical corners alike even when one sees the board turned by 180°."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from calibration.board import BoardSpec, align_pair, detect_board
from calibration.views import detect_pairs
from tracker.geometry import euler_to_matrix
from tracker.sim.boards import BoardPose, render_board
from tracker.sim.rig import default_rig

BOARD = BoardSpec(9, 6, 0.05)  # cols + rows odd: a 180° turn changes the squares' colours


def board_image(board: BoardSpec, roll_deg: float, seed: int = 0) -> np.ndarray:
    """The left camera's view of `board` 1 m away, turned `roll_deg` in its plane and tilted a little."""
    cam = default_rig().left
    R = euler_to_matrix(np.radians(12.0), np.radians(-8.0), np.radians(roll_deg))
    centre = np.array([(board.cols - 1) * board.square / 2, (board.rows - 1) * board.square / 2, 0.0])
    t = np.array([0.02, -0.01, 1.0]) - R @ centre
    img = render_board(cam, board.cols, board.rows, board.square, BoardPose(R, t), noise_sigma=1.0,
                       rng=np.random.default_rng(seed))
    return img


def turned(points: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Pixel positions after cv2.rotate(ROTATE_180) of a (w, h) image."""
    w, h = size
    return np.stack([w - 1 - points[:, 0], h - 1 - points[:, 1]], axis=1)


def test_a_board_turned_by_180_degrees_keeps_its_corner_numbers() -> None:
    for roll in (0.0, 40.0, 45.0, 50.0, 135.0, -45.0):
        img = board_image(BOARD, roll)
        a = detect_board(img, BOARD)
        b = detect_board(cv2.rotate(img, cv2.ROTATE_180), BOARD)
        assert a.corners is not None and b.corners is not None and a.oriented and b.oriented
        err = np.linalg.norm(turned(b.corners, (img.shape[1], img.shape[0])) - a.corners, axis=1)
        assert err.max() < 0.2, f"roll {roll}°: corner k of one view is not corner k of the other"


def test_a_stereo_pair_with_one_view_turned_pairs_the_same_corners(tmp_path: Path) -> None:
    """The same board seen rotated by 180° in the right camera: detect_pairs gives the right view's
    corners in the left view's physical order (the image-position rule numbered them the other way)."""
    img = board_image(BOARD, 45.0)
    names = []
    for k, roll in enumerate((45.0, 20.0, -30.0, 60.0)):
        img = board_image(BOARD, roll, seed=k)
        left, right = tmp_path / f"left{k}.png", tmp_path / f"right{k}.png"
        cv2.imwrite(str(left), img)
        cv2.imwrite(str(right), cv2.rotate(img, cv2.ROTATE_180))
        names.append((left, right))
    views = detect_pairs([n[0] for n in names], [n[1] for n in names], BOARD)
    assert views.seen.all()
    for v in range(len(names)):
        back = turned(views.obs[1, v], views.size)
        assert np.linalg.norm(back - views.obs[0, v], axis=1).max() < 0.2


def test_a_symmetric_board_is_paired_by_direction() -> None:
    """cols + rows even: the colours cannot tell a 180° turn, so the right view follows the left's order."""
    board = BoardSpec(8, 6, 0.05)
    img = board_image(board, 45.0)
    det = detect_board(img, board)
    assert det.corners is not None and not det.oriented
    shifted = det.corners + np.array([-40.0, 1.0])
    assert np.allclose(align_pair(det.corners, shifted[::-1]), shifted)
    assert np.allclose(align_pair(det.corners, shifted), shifted)
