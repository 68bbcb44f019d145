"""Which track predictions name a region (tracker.regions.hints_inside, nearest_hint): one on its pixels,
or with a reach, within that many pixels of them (a predicted centroid in a gap of the key mask's region,
endless:body, a standing walker's: searched as a new object, its legs were lost for 70 frames)."""

from __future__ import annotations

import numpy as np

from tracker.regions import hints_inside, nearest_hint


def _ring() -> np.ndarray:
    """A region (40 x 40 box) with a hole: rows and columns 10-29, less 16-23 of each."""
    r = np.zeros((40, 40), bool)
    r[10:30, 10:30] = True
    r[16:24, 16:24] = False
    return r


def test_a_prediction_on_the_regions_pixels_names_it() -> None:
    hints = np.array([[112.0, 211.0, 20.0]])  # box at (100, 200): pixel (12, 11)
    assert nearest_hint(hints, _ring(), (100, 200, 140, 240)) == 20.0


def test_a_prediction_in_a_hole_names_it_only_within_reach() -> None:
    hints = np.array([[120.0, 220.0, 20.0]])  # pixel (20, 20): 4 px from the nearest pixel of the region (24)
    box = (100, 200, 140, 240)
    assert nearest_hint(hints, _ring(), box) is None
    assert nearest_hint(hints, _ring(), box, reach_px=3) is None
    assert nearest_hint(hints, _ring(), box, reach_px=5) == 20.0


def test_a_prediction_outside_the_box_within_reach_names_it() -> None:
    r = np.zeros((20, 20), bool)
    r[:, :3] = True  # the region's pixels along the box's left edge
    hints = np.array([[98.0, 205.0, 7.0], [90.0, 205.0, 9.0]])  # 2 px and 10 px left of the box
    got = hints_inside(hints, r, (100, 200, 120, 220), reach_px=4)
    assert [float(h[2]) for h in got] == [7.0]
