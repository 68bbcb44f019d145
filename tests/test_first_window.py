"""The window a region's disparity is matched on first (tracker.strips.first_window): a person's whole outline,
any other region's central window."""

import numpy as np

from tracker.strips import MATCH_HALF, first_window


def _region(w: int, h: int) -> np.ndarray:
    m = np.zeros((h + 10, w + 10), bool)
    m[5 : 5 + h, 5 : 5 + w] = True
    return m


def test_an_upright_region_is_matched_whole() -> None:
    half = first_window(_region(40, 100))  # a walker: 2.5 times as high as wide
    assert half[0] >= 1000 and half[1] >= 1000
    assert first_window(_region(40, 60)) != MATCH_HALF  # exactly 1.5 times as high: upright


def test_round_and_wide_regions_keep_the_central_window() -> None:
    assert first_window(_region(80, 80)) == MATCH_HALF  # a ball
    assert first_window(_region(200, 70)) == MATCH_HALF  # a car side-on
    assert first_window(_region(40, 59)) == MATCH_HALF  # just under 1.5 times as high
