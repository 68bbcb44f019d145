"""The centroid's 1-σ for a target whose lowest part is lost against the ground it stands on
(tracker.bottom_edge.unseen_below, issue 12 item 1): the offset the rows down to where the ground meets the
target's depth would make."""

from __future__ import annotations

import numpy as np

from tracker.bottom_edge import unseen_below
from tracker.visibility import VisibilityConfig, padded

CFG = VisibilityConfig()
SIZE = (640, 480)
D = 9.0  # the target's disparity (px)


def _ground(h: int, w: int, contact: int) -> np.ndarray:
    """A ground whose disparity rises 0.2 px a row and equals D at row `contact` (h, w)."""
    rows = np.arange(h, dtype=np.float32)[:, None]
    return np.broadcast_to(np.float32(D) + np.float32(0.2) * (rows - contact), (h, w)).astype(np.float32)


def _plate(rows: slice, cols: slice, shape: tuple[int, int] = (200, 60)) -> np.ndarray:
    m = np.zeros(shape, bool)
    m[rows, cols] = True
    return m


def test_a_target_seen_down_to_the_ground_has_no_extra_sigma() -> None:
    mask = _plate(slice(10, 110), slice(20, 40))
    bg = _ground(*mask.shape, contact=109)  # the feet on the last mask row
    assert unseen_below(mask, D, bg, np.ones(mask.shape, bool), CFG) == (0.0, 0.0)
    assert unseen_below(mask, D, None, None, CFG) == (0.0, 0.0)  # background unknown (cameras moving)


def test_a_lost_bottom_gives_the_offset_of_the_rows_down_to_the_ground() -> None:
    mask = _plate(slice(10, 90), slice(20, 40))  # 80 rows seen, the lowest 20 lost
    bg = _ground(*mask.shape, contact=110)  # the ground meets the target's depth at row 110
    sx, sy = unseen_below(mask, D, bg, np.ones(mask.shape, bool), CFG)
    # the ground is within level_px (0.5 px, 2.5 rows) of D from row 108: the gap is rows 90-107, 18 x 20 px
    # about row 98.5; the mask (1600 px) has its centroid on row 49.5
    assert sx == 0.0 and np.isclose(sy, 360 / 1960 * 49.0)
    assert np.isclose(49.5 + sy, 58.5)  # the centroid of the plate down to row 107
    lost = np.ones(mask.shape, bool)
    lost[95:100] = False  # background not known on the way: no gap
    assert unseen_below(mask, D, bg, lost, CFG) == (0.0, 0.0)


def test_a_corner_lost_moves_the_centroid_in_x_too() -> None:
    mask = _plate(slice(10, 110), slice(20, 40))
    mask[90:110, 30:40] = False  # the bottom right corner lost
    bg = _ground(*mask.shape, contact=110)
    sx, sy = unseen_below(mask, D, bg, np.ones(mask.shape, bool), CFG)
    assert sx > 0.5 and sy > 0.5


def test_a_far_background_then_an_occluder_below_is_not_ground() -> None:
    mask = _plate(slice(10, 90), slice(20, 40))
    bg = np.full(mask.shape, 5.0, np.float32)  # a far wall just below the target ...
    bg[100:] = 14.0  # ... then a bush nearer than it: a step, not the ground rising to the target
    assert unseen_below(mask, D, bg, np.ones(mask.shape, bool), CFG) == (0.0, 0.0)
    bg = _ground(*mask.shape, contact=180)  # the ground meets D farther below than the target is tall
    assert unseen_below(mask, D, bg, np.ones(mask.shape, bool), CFG) == (0.0, 0.0)


def test_the_background_seen_between_the_legs_is_not_lost() -> None:
    mask = _plate(slice(10, 110), slice(20, 40))
    mask[70:110, 27:33] = False  # the gap between the legs, down to the ground
    bg = _ground(*mask.shape, contact=109)
    assert unseen_below(mask, D, bg, np.ones(mask.shape, bool), CFG) == (0.0, 0.0)


def test_padded_grows_the_box_below_for_the_ground() -> None:
    mask = np.ones((100, 20), bool)
    m, box = padded(mask, (100, 100, 120, 200), SIZE, below=102)
    assert box == (98, 98, 122, 302) and m.shape == (204, 24) and m[2:102, 2:22].all()
    assert padded(mask, (100, 380, 120, 480), SIZE, below=102)[1][3] == 480  # clipped to the image
