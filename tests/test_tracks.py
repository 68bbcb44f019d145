"""Identities across frames (tracker.tracks.MultiTracker): the primary target is the oldest confirmed track;
an operator's choice of another, and its undo when the choice cannot be recorded."""

from __future__ import annotations

import numpy as np

from tracker.tracks import MultiTracker, PrimaryBefore


def _two_tracks() -> MultiTracker:
    mt = MultiTracker()
    a = np.array([[100.0, 200.0, 10.0]])
    b = np.array([[100.0, 200.0, 10.0], [400.0, 220.0, 20.0]])
    mt.update(0.0, a)
    mt.update(0.033, a)  # track 1 confirmed (2 hits), the primary
    mt.update(0.066, b)  # track 2 new, one hit: not confirmed yet
    return mt


def test_the_primary_is_the_oldest_confirmed_track_until_chosen() -> None:
    mt = _two_tracks()
    assert mt.primary_id == 1 and [tr.confirmed for tr in mt.tracks] == [True, False]
    assert mt.select_primary(7) is None and mt.primary_id == 1  # no such track
    before = mt.select_primary(2)
    assert before == PrimaryBefore(primary_id=1, confirmed_id=2)  # the choice confirmed track 2
    assert mt.primary_id == 2 and all(tr.confirmed for tr in mt.tracks)
    assert mt.select_primary(1) == PrimaryBefore(primary_id=2, confirmed_id=None)  # confirmed already


def test_an_undone_choice_restores_the_primary_and_the_confirmation() -> None:
    mt = _two_tracks()
    before = mt.select_primary(2)
    assert before is not None
    mt.restore_primary(before)
    assert mt.primary_id == 1 and [tr.confirmed for tr in mt.tracks] == [True, False]
    # the primary from before has ended meanwhile: the oldest confirmed track takes its place
    mt2 = _two_tracks()
    mt2.update(0.1, np.array([[400.0, 220.0, 20.0]]))  # track 2 seen again: confirmed on its own
    before2 = mt2.select_primary(2)
    assert before2 == PrimaryBefore(primary_id=1, confirmed_id=None)
    mt2.tracks = [tr for tr in mt2.tracks if tr.track_id != 1]
    mt2.restore_primary(before2)
    assert mt2.primary_id == 2
