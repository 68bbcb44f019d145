"""Whether a verified region lies in front of its background (tracker.regions.in_front, median_behind): by
the map right behind its centre, or by the map's median behind all its pixels, which a map wrong behind
the centre alone does not mislead."""

from __future__ import annotations

import numpy as np

from tracker.bgdepth import CorrespondenceMap
from tracker.regions import in_front, median_behind

GAP, GAP_PX = 0.04, 0.5  # a 4 % depth gap and half a pixel


def _map(disparity: np.ndarray) -> CorrespondenceMap:
    h, w = disparity.shape
    z = np.zeros((h, w), np.float32)
    return CorrespondenceMap(z, z, np.ones((h, w), bool), disparity.astype(np.float32), np.zeros((h, w), np.uint8))


def test_a_walker_whose_map_is_wrong_behind_its_centre_is_in_front_by_the_median() -> None:
    # a walker at 28 px: its upper half before a hedge at 7.5 px, its lower half before ground the map
    # gives as 30 px (SGBM carried a board's disparity into it); its centre lies on the lower half
    d_map = np.full((40, 10), 7.5)
    d_map[22:] = 30.0
    obj = np.ones((40, 10), bool)
    behind = median_behind(_map(d_map), obj)
    assert behind == 7.5
    assert not in_front(28.0, 30.0, GAP, GAP_PX)
    assert in_front(28.0, behind, GAP, GAP_PX)


def test_a_patch_at_its_backgrounds_disparity_is_behind_by_both() -> None:
    d_map = np.full((20, 20), 12.0)
    obj = np.zeros((20, 20), bool)
    obj[5:15, 5:15] = True
    assert not in_front(12.2, 12.0, GAP, GAP_PX)
    assert not in_front(12.2, median_behind(_map(d_map), obj), GAP, GAP_PX)


def test_an_unknown_background_gives_no_test() -> None:
    cm = _map(np.full((5, 5), 9.0))
    cm.valid[:] = False
    assert median_behind(cm, np.ones((5, 5), bool)) == 0.0
    assert median_behind(cm, np.ones((5, 5), bool), default=9.5) == 9.5
    assert in_front(0.6, 0.0, GAP, GAP_PX)
