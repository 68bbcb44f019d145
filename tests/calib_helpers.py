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
