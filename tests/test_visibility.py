"""The centroid's uncertainty for a target seen only in part (tracker.visibility, issue 12 item 1): where
the outline meets the image border or a nearer background, the 1-σ along that axis grows."""

from __future__ import annotations

import numpy as np

from tracker.bottom_edge import occluder_below
from tracker.localize import Localizer
from tracker.rectify import Rectifier
from tracker.sim.rig import default_rig
from tracker.visibility import (
    VisibilityConfig,
    cut_and_skew,
    cut_sides,
    cut_sigma_px,
    cuts,
    extra_sigma_px,
    object_and_shadow,
    padded,
    painted,
    with_objects,
)

CFG = VisibilityConfig()
SIZE = (640, 480)


def _person(box: tuple[int, int, int, int], rows: slice) -> np.ndarray:
    """A mask over box with the rows `rows` of a 20 px wide figure set, centred in the box."""
    x0, y0, x1, y1 = box
    m = np.zeros((y1 - y0, x1 - x0), bool)
    c = (x1 - x0) // 2
    m[rows, c - 10:c + 10] = True
    return m


def test_a_target_wholly_in_view_before_a_far_background_is_not_cut() -> None:
    box = (100, 100, 160, 220)
    mask = _person(box, slice(10, 110))
    bg = np.full(mask.shape, 5.0, np.float32)  # background farther than the target (disparity 9 px)
    assert cut_sides(mask, box, SIZE, 9.0, bg, np.ones(mask.shape, bool), CFG) == (0, 0)
    assert cut_sides(mask, box, SIZE, 9.0, None, None, CFG) == (0, 0)


def test_the_image_border_cuts_a_target() -> None:
    box = (100, 400, 160, 480)
    mask = _person(box, slice(10, 80))  # down to the bottom row of the image
    assert cut_sides(mask, box, SIZE, 9.0, None, None, CFG) == (0, 1)
    box = (0, 100, 40, 220)
    mask = np.zeros((120, 40), bool)
    mask[10:110, 0:20] = True  # from the left edge of the image
    assert cut_sides(mask, box, SIZE, 9.0, None, None, CFG) == (1, 0)
    mask[:, :11] = False  # from column 11 = disparity 9 + 2: the right camera does not see columns 0-8
    assert cut_sides(mask, box, SIZE, 9.0, None, None, CFG) == (1, 0)
    mask[:, 11] = False
    assert cut_sides(mask, box, SIZE, 9.0, None, None, CFG) == (0, 0)


def test_a_nearer_background_below_cuts_a_target_and_a_farther_one_does_not() -> None:
    box = (100, 100, 160, 220)
    mask = _person(box, slice(10, 70))  # the legs hidden from row 70 of the box on
    bg = np.full(mask.shape, 5.0, np.float32)
    bg[70:] = 12.0  # a hedge nearer than the target (disparity 9 px)
    valid = np.ones(mask.shape, bool)
    assert cut_sides(mask, box, SIZE, 9.0, bg, valid, CFG) == (0, 1)
    assert cut_sides(mask, box, SIZE, 9.0, bg, np.zeros(mask.shape, bool), CFG) == (0, 0)  # not known there
    bg[70:] = 9.2  # within nearer_px of the target: the ground it stands on, not an occluder ...
    bg[60:70] = 8.8  # ... which runs on behind its feet (no step in the background at the outline)
    assert cut_sides(mask, box, SIZE, 9.0, bg, valid, CFG) == (0, 0)
    bg[60:70] = 5.0  # a step from far behind the target to slightly before it: a low wall
    assert cut_sides(mask, box, SIZE, 9.0, bg, valid, CFG) == (0, 1)


def test_the_extra_sigma_is_kappa_times_the_visible_extent_per_cut_side() -> None:
    mask = np.zeros((100, 50), bool)
    mask[10:70, 5:25] = True  # 20 x 60 px
    assert extra_sigma_px(mask, (0, 1), CFG) == (0.0, CFG.kappa * 60)
    sx, sy = extra_sigma_px(mask, (2, 0), CFG)
    assert np.isclose(sx, CFG.kappa * 20 * np.sqrt(2)) and sy == 0.0
    assert extra_sigma_px(mask, (0, 1), CFG, 44.0) == (0.0, 22.0)  # half an occluder 44 px tall below
    assert np.isclose(extra_sigma_px(mask, (0, 2), CFG, 44.0)[1], np.hypot(CFG.kappa * 60, 22.0))  # and the top
    assert extra_sigma_px(mask, (1, 0), CFG, 44.0) == (CFG.kappa * 20, 0.0)  # no y side cut: no occluder term


def test_a_corner_hidden_by_a_round_occluder_moves_the_centroid_along_the_cut_side() -> None:
    """A board 40 x 80 px whose lower left corner is behind a nearer round bush: only its bottom side is
    cut, yet its visible centroid lies right of (and above) the whole board's. The 1-σ along x covers
    that move; a bottom hidden evenly moves the centroid along y only."""
    box, shape = (100, 100, 200, 220), (120, 100)
    board = np.zeros(shape, bool)
    board[10:90, 30:70] = True
    yy, xx = np.mgrid[:shape[0], :shape[1]]
    valid = np.ones(shape, bool)
    for radius in (20, 30):
        bush = (xx - 30) ** 2 + (yy - 90) ** 2 <= radius**2
        mask = board & ~bush
        bg = np.where(bush, 12.0, 5.0).astype(np.float32)  # the bush nearer than the board (disparity 9 px)
        cut, (sx, sy) = cut_and_skew(mask, box, SIZE, 9.0, bg, valid, CFG)
        moved = np.nonzero(mask)[1].mean() - np.nonzero(board)[1].mean()  # 1.2 and 2.0 px
        assert cut == (0, 1) and sy == 0.0
        assert moved <= sx <= CFG.kappa * 40  # covered, and no more than a cut side along x would add
    mask = board.copy()
    mask[70:] = False
    bg = np.full(shape, 5.0, np.float32)
    bg[70:] = 12.0
    cut, (sx, sy) = cut_and_skew(mask, box, SIZE, 9.0, bg, valid, CFG)
    assert cut == (0, 1) and abs(sx) < 1e-9 and sy == 0.0
    assert cut_and_skew(mask, box, SIZE, 9.0, None, None, CFG) == ((0, 0), (0.0, 0.0))


def test_the_occluder_below_a_target_bounds_how_much_of_it_is_hidden() -> None:
    """A head 12 px tall above a hedge 24 px tall: the walker goes on behind it down to its feet, at
    most 24 px, so the centroid may lie up to 12 px high, where kappa times the visible height says
    4.8. A hedge behind the target, or none, bounds nothing."""
    box, shape = (100, 100, 160, 180), (80, 60)
    mask = np.zeros(shape, bool)
    mask[10:22, 20:40] = True
    bg = np.full(shape, 3.0, np.float32)
    bg[22:46, :] = 7.3  # the hedge, nearer than the walker (disparity 6.6), from the row below the head
    valid = np.ones(shape, bool)
    assert cut_sides(mask, box, SIZE, 6.6, bg, valid, CFG) == (0, 1)
    assert occluder_below(mask, 6.6, bg, valid, CFG) == 24.0
    bg[22:46, :] = 6.0  # behind the walker: nothing hides it
    assert occluder_below(mask, 6.6, bg, valid, CFG) is None
    bg[22:46, :] = 7.3
    bg[22:26, :] = 3.0  # the hedge starts 4 rows below: it does not meet the outline
    assert occluder_below(mask, 6.6, bg, valid, CFG) is None
    assert occluder_below(mask, 6.6, None, None, CFG) is None


def test_the_localizer_widens_only_the_cut_axis() -> None:
    loc = Localizer(Rectifier(default_rig()))
    c = np.array([300.0, 250.0])
    plain = loc.locate(c, 20.0, 0.05, 1200, None)
    cut = loc.locate(c, 20.0, 0.05, 1200, None, (0.0, 24.0))
    assert (cut.r, cut.theta, cut.phi) == (plain.r, plain.theta, plain.phi)
    assert cut.sigma_phi > 20 * plain.sigma_phi
    assert np.isclose(cut.sigma_phi, 24.0 / 600.0, rtol=0.1)  # 24 px at f = 600 px, in radians
    assert np.isclose(cut.sigma_theta, plain.sigma_theta, rtol=0.05)


def test_a_nearer_background_just_outside_a_tight_box_cuts_the_target() -> None:
    mask = np.ones((60, 20), bool)  # the mask fills its box: no ring inside it
    mask[:, :2] = False
    mask[:, 2:4] = True
    m2, b2 = padded(mask[:, 2:], (102, 100, 120, 160), SIZE)
    assert b2 == (100, 98, 122, 162) and m2.shape == (64, 22) and m2[2:62, 2:20].all() and not m2[:, :2].any()
    bg = np.full(m2.shape, 5.0, np.float32)
    bg[:, :2] = 14.0  # a post nearer than the target (disparity 9 px) just left of it
    valid = np.ones(m2.shape, bool)
    assert cut_sides(mask[:, 2:], (102, 100, 120, 160), SIZE, 9.0, bg[2:62, 2:20], valid[2:62, 2:20], CFG) == (0, 0)
    assert cut_sides(m2, b2, SIZE, 9.0, bg, valid, CFG) == (1, 0)
    assert padded(mask, (0, 0, 20, 60), SIZE)[1] == (0, 0, 22, 62)  # clipped to the image


def test_a_nearer_background_a_shadow_band_left_of_the_target_cuts_it() -> None:
    box = (100, 100, 140, 160)
    mask = np.zeros((60, 40), bool)
    mask[:, 20:40] = True
    bg = np.full(mask.shape, 5.0, np.float32)
    bg[:, :14] = 15.0  # a post at disparity 15 before a target at 9: the right camera misses 6 columns
    valid = np.ones(mask.shape, bool)
    assert cut_sides(mask, box, SIZE, 9.0, bg, valid, CFG) == (1, 0)
    bg[:, :14] = 12.0  # nearer by 3 px only: its shadow ends 3 columns short of the ring
    assert cut_sides(mask, box, SIZE, 9.0, bg, valid, CFG) == (0, 0)
    mask[:, 20:40], mask[:, 0:20] = False, True
    bg[:, :] = 5.0
    bg[:, 20:] = 15.0  # the same post right of the target hides it with no band between
    assert cut_sides(mask, box, SIZE, 9.0, bg, valid, CFG) == (1, 0)
    bg[:, 20:] = 5.0
    bg[:, 30:] = 15.0  # ... and one 10 columns off does not
    assert cut_sides(mask, box, SIZE, 9.0, bg, valid, CFG) == (0, 0)


def test_the_shadow_band_of_a_nearer_bush_below_left_cuts_the_bottom() -> None:
    box = (100, 100, 160, 220)
    mask = _person(box, slice(10, 110))  # columns 20-39
    mask[70:110, 20:34] = False  # the legs' left part hidden: only a 6-px strip goes on down
    bg = np.full(mask.shape, 5.0, np.float32)
    bg[70:, :24] = 19.0  # a bush at disparity 19 before the target at 9: the right camera misses 10 columns
    valid = np.ones(mask.shape, bool)
    assert cut_sides(mask, box, SIZE, 9.0, bg, valid, CFG)[1] == 1
    bg[70:, :24] = 5.0
    assert cut_sides(mask, box, SIZE, 9.0, bg, valid, CFG) == (0, 0)


def test_another_object_nearer_than_the_target_cuts_it_and_a_farther_one_does_not() -> None:
    box = (100, 100, 160, 220)
    mask = _person(box, slice(10, 110))  # columns 20-39
    bg = np.full(mask.shape, 5.0, np.float32)
    valid = np.ones(mask.shape, bool)
    crosser = np.ones((100, 30), bool)  # another object, columns 50-79 of the box's frame, at disparity 20
    at = (150, 105, 180, 205)
    disp, ok = with_objects(bg, valid, box, [(at, crosser, 20.0)])
    assert disp is not None and ok is not None
    assert cut_sides(mask, box, SIZE, 9.0, disp, ok, CFG) == (0, 0)  # 10 columns off the target
    # with its occlusion shadow, 20 - 5 = 15 columns to its left, it reaches the target's right side
    others = object_and_shadow(at, crosser, 20.0, 5.0)
    disp, ok = with_objects(bg, valid, box, others)
    assert disp is not None and ok is not None and disp[50, 35] == 20.0 and disp[50, 34] == 5.0
    assert cut_sides(mask, box, SIZE, 9.0, disp, ok, CFG, painted(box, others)) == (1, 0)
    disp, ok = with_objects(bg, valid, box, object_and_shadow(at, crosser, 4.0, 3.0))  # behind the target
    assert cut_sides(mask, box, SIZE, 9.0, disp, ok, CFG) == (0, 0)
    disp, ok = with_objects(None, None, box, others)  # cameras moving
    assert cut_sides(mask, box, SIZE, 9.0, disp, ok, CFG, painted(box, others)) == (1, 0)
    assert with_objects(None, None, box, [((300, 300, 310, 310), crosser, 20.0)]) == (None, None)


def test_a_hedge_slightly_nearer_cuts_where_the_background_steps_and_the_ground_does_not() -> None:
    box = (100, 100, 160, 220)
    mask = _person(box, slice(10, 70))  # the legs hidden from row 70 of the box on
    valid = np.ones(mask.shape, bool)
    bg = np.full(mask.shape, 3.0, np.float32)  # a far wall behind the target (disparity 7 px)
    bg[70:] = 7.4  # a hedge 0.4 px nearer than the target: under nearer_px
    assert cut_sides(mask, box, SIZE, 7.0, bg, valid, CFG) == (0, 1)
    rows = np.arange(mask.shape[0], dtype=np.float32)[:, None]
    ground = np.broadcast_to(7.0 + 0.2 * (rows - 69.0), mask.shape).astype(np.float32)
    assert cut_sides(mask, box, SIZE, 7.0, ground, valid, CFG) == (0, 0)  # the ground the target stands on
    bg[70:] = 6.7  # a hedge as far as the target, within level_px: the target may go on into it unseen
    assert cut_sides(mask, box, SIZE, 7.0, bg, valid, CFG) == (0, 1)
    bg[70:] = 6.2  # a background well behind the target below it: seen, not hidden
    assert cut_sides(mask, box, SIZE, 7.0, bg, valid, CFG) == (0, 0)
    bg[70:] = 7.4
    no_jump = bg.copy()
    no_jump[:70] = 6.5  # the background just behind the outline is not much farther: no step
    assert cut_sides(mask, box, SIZE, 7.0, no_jump, valid, CFG) == (0, 0)


def test_below_only_a_background_stepping_forward_from_behind_the_target_cuts_it() -> None:
    box = (100, 100, 160, 220)
    mask = _person(box, slice(10, 70))  # the lowest row 69
    valid = np.ones(mask.shape, bool)
    bg = np.full(mask.shape, 3.0, np.float32)  # a far wall (disparity 3) behind the target at 9
    bg[70:] = 12.0  # a hedge before it from the row below on: steps forward by 9 px
    assert cut_sides(mask, box, SIZE, 9.0, bg, valid, CFG) == (0, 1)
    # a steeper ground the target stands on, 0.25 px a row, read 2 px too near all over by the matcher:
    # nearer than the target below it, but as near behind its lowest rows, 1.25 px over six rows
    rows = np.arange(mask.shape[0], dtype=np.float32)[:, None]
    ground = np.broadcast_to(11.0 + 0.25 * (rows - 69.0), mask.shape).astype(np.float32)
    assert cut_sides(mask, box, SIZE, 9.0, ground, valid, CFG) == (0, 0)
    wrong = bg.copy()
    wrong[66:70, 20:40] = 12.0  # a blotch of the hedge's disparity behind the target's lowest 4 rows too
    assert cut_sides(mask, box, SIZE, 9.0, wrong, valid, CFG) == (0, 0)


def test_the_ground_below_a_target_cut_at_its_side_does_not_move_it_along_y() -> None:
    box = (100, 100, 160, 220)
    mask = _person(box, slice(10, 70))  # columns 20-39, rows 10-69
    valid = np.ones(mask.shape, bool)
    bg = np.full(mask.shape, 3.0, np.float32)  # a far wall
    rows = np.arange(mask.shape[0], dtype=np.float32)[:, None]
    ground = np.broadcast_to(9.0 + 0.2 * (rows - 69.0), mask.shape)
    bg[50:] = ground[50:]  # the ground it stands on, at its own depth below it: level, but no side it cuts
    bg[:, :19] = 14.0  # a post before its left side
    cut, (sx, sy) = cut_and_skew(mask, box, SIZE, 9.0, bg, valid, CFG)
    assert cut == (1, 0) and sx == 0.0
    assert sy < 0.5  # the post's ring is even about the centroid: no move along y


def test_an_occluder_below_bounds_the_bottoms_term_only_where_it_cuts_the_bottom() -> None:
    """A target 20 x 21 px whose top right meets a post's learnt disparity, which runs on down past it and
    under its own right part (the learnt map's band left of a post, seen from the pivot): the top and the
    right side are cut, the bottom is not (no step forward below it). The 58 px of post below would have
    made the y 1-σ 29 px; the top's own term is kappa times the visible height."""
    box, shape = (100, 100, 160, 200), (100, 60)
    mask = np.zeros(shape, bool)
    mask[20:41, 20:41] = True
    bg = np.full(shape, 3.0, np.float32)
    bg[:, 32:46] = 9.0  # nearer than the target (6.0)
    valid = np.ones(shape, bool)
    c = cuts(mask, box, SIZE, 6.0, bg, valid, CFG)
    assert c.sides == (False, True, True, False) and not c.bottom_by_background
    tall = occluder_below(mask, 6.0, bg, valid, CFG)
    assert tall is not None and tall > 50  # what the map offers below: not the bottom's bound here
    assert cut_sigma_px(mask, c, CFG, tall) == extra_sigma_px(mask, (1, 1), CFG) == (CFG.kappa * 21, CFG.kappa * 21)
    bg[:, 32:46] = 3.0
    bg[41:, 20:41] = 9.0  # a hedge below the whole target, from the row under it: the bottom is cut by it
    c = cuts(mask, box, SIZE, 6.0, bg, valid, CFG)
    assert c.sides == (False, False, False, True) and c.bottom_by_background
    assert cut_sigma_px(mask, c, CFG, occluder_below(mask, 6.0, bg, valid, CFG)) == (0.0, 29.5)
