"""A region that fails as a new object, with a track predicted in its rows beyond a nearer background next to
it (a car's piece left of the post it passes behind), is verified at that track's disparity as a part only,
kept where it joins the rest (tracker.regions.beyond_occluder_hints, tracker.split.join_occluded); a part
only claims no track for the temporal stage's one-camera sightings (tracker.temporal._unclaimed)."""

from __future__ import annotations

import numpy as np
import pytest
from sim_helpers import walker_errors

import tracker.verify as verify
from tracker.bgdepth import CorrespondenceMap
from tracker.regions import beyond_occluder_hints
from tracker.results import Blob
from tracker.temporal import _unclaimed


def _map(near_cols: slice, h: int = 40, w: int = 60) -> CorrespondenceMap:
    """A box's map: background at 7 px, and at 22 px (a post nearer than a body at 16 px) over near_cols."""
    disp = np.full((h, w), 7.0, np.float32)
    disp[:, near_cols] = 22.0
    z = np.zeros((h, w), np.float32)
    return CorrespondenceMap(z, z, np.ones((h, w), bool), disp, np.zeros((h, w), np.uint8))


def test_a_track_beyond_a_nearer_background_next_to_the_region_gives_its_disparity() -> None:
    region = np.zeros((40, 60), bool)
    region[5:35, 10:30] = True  # columns 110-129 of the image, rows 205-234
    box = (100, 200, 160, 240)
    right, left, below = [200.0, 220.0, 16.0], [60.0, 220.0, 17.0], [200.0, 260.0, 15.0]
    hints = np.array([right, below])
    assert beyond_occluder_hints(hints, region, box, _map(slice(30, 36)), 0.04, 0.5) == [16.0]
    assert beyond_occluder_hints(hints, region, box, _map(slice(0, 0)), 0.04, 0.5) == []  # nothing nearer
    assert beyond_occluder_hints(hints, region, box, _map(slice(4, 10)), 0.04, 0.5) == []  # on the other side
    assert beyond_occluder_hints(np.array([left]), region, box, _map(slice(4, 10)), 0.04, 0.5) == [17.0]
    assert beyond_occluder_hints(np.array([below]), region, box, _map(slice(30, 36)), 0.04, 0.5) == []
    assert beyond_occluder_hints(None, region, box, _map(slice(30, 36)), 0.04, 0.5) == []


def test_a_part_only_claims_no_track() -> None:
    coast = np.array([[50.0, 270.0, 12.0, 1, 0.05, 0.03]])
    mask = np.ones((20, 20), bool)
    part = Blob((30, 260, 70, 280), mask, 400, np.array([50.0, 270.0]), np.array([50.0, 270.0]), 12.0, 0.05,
                3.0, 0.97, part_only=True)
    assert np.array_equal(_unclaimed(lambda: coast, [part], 40.0), coast)
    whole = Blob((30, 260, 70, 280), mask, 400, np.array([50.0, 270.0]), np.array([50.0, 270.0]), 12.0, 0.05,
                 3.0, 0.97)
    assert _unclaimed(lambda: coast, [whole], 40.0).shape == (0, 6)


def test_the_cars_piece_left_of_the_post_joins_it(monkeypatch: pytest.MonkeyPatch) -> None:
    # occlusion:body frame 195: the piece (823 px of the car's 13,275) verified anew failed and was left out,
    # the centroid 6.4 px off; at the car's disparity, joined, 0.7 px when measured
    got = walker_errors("occlusion:body", 195)
    assert len(got) == 1 and got[0] < 2.0
    monkeypatch.setattr(verify, "beyond_occluder_hints", lambda *a: [])
    got = walker_errors("occlusion:body", 195)
    assert len(got) == 1 and got[0] > 5.0
