"""Candidate boxes one above the other are verified together (tracker.boxes.stacked_joined): a standing
walker's torso and feet, eq. (9) firing on neither knee between; boxes side by side (a car split by a post)
and boxes far apart stay as they are. A box that holds a track's prediction reaches over the rows its outline
reached lately (tracker.boxes.TrackSpans)."""

from __future__ import annotations

import numpy as np

from tracker.boxes import TrackSpans, stacked_joined


def test_a_box_under_another_within_a_few_pixels_joins_it() -> None:
    torso, feet = (66, 218, 150, 310), (94, 314, 118, 338)  # endless:body, frame 80: 4 px apart
    assert stacked_joined([torso, feet], [40, 3]) == (((66, 218, 150, 338),), (43,))


def test_overlapping_stacked_boxes_join_whatever_their_order() -> None:
    head, body, legs = (20, 0, 40, 22), (10, 18, 50, 80), (15, 76, 45, 120)
    assert stacked_joined([legs, head, body], [5, 2, 30]) == (((10, 0, 50, 120),), (37,))


def test_boxes_side_by_side_stay_apart() -> None:
    left, right = (0, 100, 60, 200), (50, 100, 110, 200)  # overlapping by 10 px across, the whole height
    assert stacked_joined([left, right], [10, 12]) == ((left, right), (10, 12))


def test_a_box_further_below_or_to_the_side_stays_apart() -> None:
    top = (100, 100, 160, 200)
    below = (100, 212, 160, 260)  # 12 px below
    aside = (150, 205, 230, 260)  # 5 px below, overlapping 10 of its 80 px across
    assert stacked_joined([top, below, aside], [1, 2, 3]) == ((top, below, aside), (1, 2, 3))


def _spans() -> TrackSpans:
    """Track 3's outline over rows 100-199 with its centroid at row 120 and d = 20 px: 1 px above and 4 px
    below the centroid per px of disparity."""
    spans = TrackSpans()
    mask = np.ones((100, 30), bool)
    spans.keep(3, (50, 100, 80, 200), mask, 120.0, 20.0)
    return spans


def test_a_tracked_bodys_box_reaches_over_the_rows_its_outline_reached_lately() -> None:
    # predicted at row 130 with d = 10 px (twice as far): rows 120 to 170, plus the 8 px margin
    hints = np.array([[60.0, 130.0, 10.0]])
    assert _spans().widened(((40, 125, 90, 150),), hints, [3], 480, 8) == ((40, 112, 90, 179),)


def test_a_box_without_the_tracks_prediction_or_of_another_track_is_left_as_it_is() -> None:
    boxes = ((200, 110, 240, 150), (40, 110, 90, 150))
    hints = np.array([[60.0, 130.0, 10.0]])
    assert _spans().widened(boxes, hints, [4], 480, 8) == boxes  # track 4: nothing kept of it
    assert _spans().widened(boxes[:1], hints, [3], 480, 8) == boxes[:1]  # the prediction lies in neither


def test_the_widened_box_stays_within_the_image() -> None:
    hints = np.array([[60.0, 450.0, 20.0]])
    assert _spans().widened(((40, 430, 90, 470),), hints, [3], 480, 8) == ((40, 422, 90, 480),)
