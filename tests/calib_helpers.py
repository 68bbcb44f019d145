"""Shared helpers for the calibration tests: the shared test-data folder (skip when absent)."""

from __future__ import annotations

from pathlib import Path

import pytest

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
CHESS = DATA / "chessboards"


def chess_dir() -> Path:
    """../shared/data/chessboards, or skip the test with the reason."""
    if not (CHESS / "calib1.dat").is_file():
        pytest.skip(f"shared test data not found at {CHESS} (OpenCV chessboard images, see data README)")
    return CHESS


def write_sim_pairs(folder: Path, n: int, seed: int = 0) -> tuple[str, str]:
    """Render n stereo pairs of a 9x6 board (0.05 m squares) seen by the simulated rig into folder/left
    and folder/right as PNG; returns the two globs."""
    import cv2
    import numpy as np

    from calibration.scenario import BOARD, sample_poses
    from tracker.sim.boards import render_board
    from tracker.sim.rig import default_rig

    rig = default_rig()
    rng = np.random.default_rng(seed)
    for side in ("left", "right"):
        (folder / side).mkdir(parents=True, exist_ok=True)
    for v, pose in enumerate(sample_poses(rng, n, rig)):
        for side, cam in (("left", rig.left), ("right", rig.right)):
            img = render_board(cam, BOARD.cols, BOARD.rows, BOARD.square, pose, noise_sigma=1.0, rng=rng)
            cv2.imwrite(str(folder / side / f"view{v:02d}.png"), img)
    return str(folder / "left" / "*.png"), str(folder / "right" / "*.png")
