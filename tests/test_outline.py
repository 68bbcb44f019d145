"""The centroid's uncertainty from a warped outline's edge (tracker.outline, issue 12 item 1)."""

from __future__ import annotations

import numpy as np

from tracker.outline import OutlineConfig, warped_outline_sigma_px


def test_a_square_gets_sigma_b_times_the_root_sum_of_its_edge_distances_over_its_area() -> None:
    mask = np.zeros((41, 41), bool)
    mask[10:31, 10:31] = True  # 21 x 21 px about (20, 20)
    # edge: the 2 columns at |dx| = 10 (21 px each) and the top and bottom rows' 19 other pixels
    sum_dx2 = 2 * 21 * 100 + 2 * sum(x * x for x in range(-9, 10))
    sx, sy = warped_outline_sigma_px(mask, OutlineConfig((1.0, 0.4)))
    assert np.isclose(sx, np.sqrt(sum_dx2) / 441.0) and np.isclose(sy, 0.4 * np.sqrt(sum_dx2) / 441.0)


def test_a_larger_target_is_located_more_precisely_and_an_empty_mask_adds_nothing() -> None:
    small, large = np.zeros((100, 100), bool), np.zeros((100, 100), bool)
    small[40:60, 40:60] = True
    large[10:90, 10:90] = True
    cfg = OutlineConfig()
    assert warped_outline_sigma_px(large, cfg)[0] < 0.6 * warped_outline_sigma_px(small, cfg)[0]
    assert warped_outline_sigma_px(np.zeros((5, 5), bool), cfg) == (0.0, 0.0)


def test_a_mask_at_its_box_edge_counts_that_edge() -> None:
    mask = np.zeros((21, 21), bool)
    mask[:, :] = True  # the whole box: its border is the edge
    sx, _ = warped_outline_sigma_px(mask, OutlineConfig((1.0, 1.0)))
    assert sx > 0.1
