"""Candidate boxes one above the other are verified together (tracker.boxes.stacked_joined): a standing
walker's torso and feet, eq. (9) firing on neither knee between; boxes side by side (a car split by a post)
and boxes far apart stay as they are."""

from __future__ import annotations

from tracker.boxes import stacked_joined


def test_a_box_under_another_within_a_few_pixels_joins_it() -> None:
    torso, feet = (66, 218, 150, 310), (94, 314, 118, 338)  # endless:body, frame 80: 4 px apart
    assert stacked_joined([torso, feet], [40, 3]) == (((66, 218, 150, 338),), (43,))


def test_overlapping_stacked_boxes_join_whatever_their_order() -> None:
    head, body, legs = (20, 0, 40, 22), (10, 18, 50, 80), (15, 76, 45, 120)
    assert stacked_joined([legs, head, body], [5, 2, 30]) == (((10, 0, 50, 120),), (37,))


def test_boxes_side_by_side_stay_apart() -> None:
    left, right = (0, 100, 60, 200), (50, 100, 110, 200)  # overlapping by 10 px across, the whole height
    assert stacked_joined([left, right], [10, 12]) == ((left, right), (10, 12))


def test_a_box_within_0_4_of_the_taller_ones_height_below_joins() -> None:
    # endless:body frames 457 and 456: a walker's upper body over a nearer box, one leg beside the box 20 and
    # 32 px below; 0.4 of 84 px is 33.6 px
    torso = (110, 218, 182, 302)
    assert stacked_joined([torso, (114, 322, 150, 382)], [30, 6]) == (((110, 218, 182, 382),), (36,))
    assert stacked_joined([torso, (114, 334, 150, 382)], [30, 6]) == (((110, 218, 182, 382),), (36,))
    assert stacked_joined([torso, (114, 337, 150, 382)], [30, 6])[0] == (torso, (114, 337, 150, 382))  # 35 px


def test_a_box_further_below_or_to_the_side_stays_apart() -> None:
    top = (100, 100, 160, 200)
    below = (100, 245, 160, 290)  # 45 px below, over 0.4 of the taller box's 100 px
    aside = (150, 205, 230, 260)  # 5 px below, overlapping 10 of its 80 px across
    assert stacked_joined([top, below, aside], [1, 2, 3]) == ((top, below, aside), (1, 2, 3))
