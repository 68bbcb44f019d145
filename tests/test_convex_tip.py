"""A convex body's own bottom resting on a nearer edge is not a cut (tracker.visibility.convex_tip): a ball seen
above a hedge's line keeps its sharp 1-σ; a body the hedge does cut, one whose outline the occluder follows
along its lower side, and a cut side's ragged lowest row stay cut."""

from __future__ import annotations

import cv2
import numpy as np

from tracker.visibility import VisibilityConfig, cut_and_skew

CFG = VisibilityConfig()
SIZE = (640, 480)
BOX = (100, 100, 140, 140)  # 40 x 40 px; the hedge's top at row 26 of it
D, FAR, NEAR = 9.0, 5.0, 12.0


def _ball(cy: int) -> np.ndarray:
    """A disc of radius 7 px centred at (20, cy) of the box: its lowest row at cy + 7."""
    m = np.zeros((40, 40), np.uint8)
    cv2.circle(m, (20, cy), 7, 1, -1)
    return m.astype(bool)


def _hedge() -> tuple[np.ndarray, np.ndarray]:
    """A wall behind the target (disparity FAR), a nearer hedge (NEAR) from row 26 of the box down."""
    bg = np.full((40, 40), FAR, np.float32)
    bg[26:] = NEAR
    return bg, np.ones(bg.shape, bool)


def test_a_ball_resting_on_a_hedges_line_is_seen_whole() -> None:
    bg, valid = _hedge()
    ball = _ball(18)  # its lowest row 25, the hedge from 26
    cut, (sx, sy) = cut_and_skew(ball, BOX, SIZE, D, bg, valid, CFG)
    assert cut == (0, 0)
    assert 0.0 < sy < 0.2 and sx < 0.05  # a cap under a pixel row deep, anything from none to all of it
    board = np.zeros((40, 40), bool)
    board[12:26, 13:28] = True  # a board there is cut: it may go on behind the hedge
    assert cut_and_skew(board, BOX, SIZE, D, bg, valid, CFG)[0] == (0, 1)


def test_a_ball_the_hedge_cuts_is_cut() -> None:
    bg, valid = _hedge()
    ball = _ball(24)
    ball[26:] = False  # its lower part behind the hedge: rows as wide as those above end the outline
    assert cut_and_skew(ball, BOX, SIZE, D, bg, valid, CFG)[0] == (0, 1)


def test_a_ball_in_a_nearer_cup_is_cut() -> None:
    # the nearer background follows the ball's whole lower arc, as a bush's round top follows what it hides
    ball = _ball(18)
    bg = np.full((40, 40), FAR, np.float32)
    cup = (cv2.dilate(ball.view(np.uint8), np.ones((7, 7), np.uint8)) > 0) & ~ball
    cup[:19] = False
    bg[cup] = NEAR
    assert cut_and_skew(ball, BOX, SIZE, D, bg, np.ones(bg.shape, bool), CFG)[0][1] == 1  # (its sides too)


def test_a_cut_sides_ragged_lowest_row_is_no_tip() -> None:
    bg, valid = _hedge()
    board = np.zeros((40, 40), bool)
    board[14:26, 14:26] = True
    board[24, 14:16] = False
    board[25, 14:19] = False  # the lowest rows short at their left end: 12, 10 and 7 px, the right end kept
    assert cut_and_skew(board, BOX, SIZE, D, bg, valid, CFG)[0] == (0, 1)
    board[25, 14:26] = False
    board[25, 20] = True  # a stray pixel under a flat cut
    assert cut_and_skew(board, BOX, SIZE, D, bg, valid, CFG)[0] == (0, 1)
