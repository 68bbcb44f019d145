"""The disparity's 1-σ from the scatter of its parts (tracker.disparity_sigma, issue 12 item 1)."""

from __future__ import annotations

import numpy as np

from tracker.disparity_sigma import COLUMNS, MIN_PARTS, ROWS, grid_parts, scatter_sigma
from tracker.stereo import refine_region


def test_the_parts_tile_the_window_and_leave_the_rest_out() -> None:
    mask = np.zeros((100, 120), bool)
    mask[10:90, 20:100] = True  # 80 x 80 px, larger than the 48 x 32 window
    parts = grid_parts(mask, (60.0, 50.0), (24, 16))
    assert len(parts) == COLUMNS * ROWS
    union = np.logical_or.reduce(parts)
    assert union.sum() == 48 * 32 and union[34:66, 36:84].all()
    assert sum(int(p.sum()) for p in parts) == 48 * 32  # no pixel in two parts
    small = np.zeros((40, 40), bool)
    small[10:30, 12:28] = True  # smaller than the window: the parts tile the mask
    assert np.logical_or.reduce(grid_parts(small, (20.0, 20.0), (24, 16))).sum() == small.sum()


def test_the_sigma_is_the_standard_error_of_the_parts_mean() -> None:
    d = [10.0, 10.2, 9.8, 10.1, 9.9, 10.0, 10.3, 9.7]
    assert np.isclose(scatter_sigma(d), np.std(d, ddof=1) / np.sqrt(8))
    assert scatter_sigma(d[:MIN_PARTS - 1]) == 0.0
    assert scatter_sigma([12.0] * 8) == 0.0


def _pair(slope: float) -> tuple[np.ndarray, np.ndarray]:
    """A textured surface whose disparity is 10 px + slope px per column (a surface turned from the axis)."""
    rng = np.random.default_rng(3)
    tex = np.repeat(np.repeat(rng.uniform(30, 220, (64, 64)), 3, axis=0), 3, axis=1)[:120, :]
    xs = np.arange(160, dtype=float)
    left = np.zeros((120, 160))
    right = np.zeros((120, 160))
    for y in range(120):
        left[y] = np.interp(xs, np.arange(192), tex[y])
        right[y] = np.interp(xs + 10.0 + slope * (xs - 80.0), np.arange(192), tex[y])
    return left.clip(0, 255).astype(np.uint8), right.clip(0, 255).astype(np.uint8)


def test_the_parts_of_a_slanted_surface_disagree_and_of_a_flat_one_agree() -> None:
    def sigma(slope: float) -> float:
        left, right = _pair(slope)
        mask = np.zeros((40, 60), bool)
        mask[:, :] = True
        ds = []
        for p in grid_parts(mask, (30.0, 20.0), (24, 16)):
            fit = refine_region(left, right, p, 50, 40, 10.0)
            if fit is not None:
                ds.append(fit.disparity)
        return scatter_sigma(ds)
    flat, slanted = sigma(0.0), sigma(0.02)  # 0.02 px a column: 1 px over the 48-px window
    assert flat < 0.02 and slanted > 5 * flat and slanted > 0.05
