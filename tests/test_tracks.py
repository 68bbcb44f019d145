"""Identities across frames (tracker.tracks.MultiTracker): the primary target is the oldest confirmed track;
an operator's choice of another, and its undo when the choice cannot be recorded; a track begun beside the
primary is taken over by it when the primary misses a frame; a primary unseen past its hold yields to a
target in view."""

from __future__ import annotations

import numpy as np

from tracker.tracks import MultiTracker, PrimaryBefore, TrackerConfig


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


def _primary_at(y: float) -> MultiTracker:
    mt = MultiTracker()
    for k in range(3):
        mt.update(k / 30, np.array([[324.0, y, 8.6]]))
    assert mt.primary_id == 1
    return mt


def test_a_part_split_off_the_primary_goes_on_as_the_primary() -> None:
    """Live on the endless scene: a fading target's outline split in two (its bottom and its top, 24 px
    apart); the bottom kept the primary's id, the top began a track, then the bottom was gone. Before, the
    top's track took the sightings and the primary coasted, not detected, for 45 frames."""
    mt = _primary_at(250.0)
    both = mt.update(3 / 30, np.array([[324.0, 250.0, 8.6], [324.0, 226.0, 8.6]]))
    assert both == [1, 2] and mt.get(2) is not None and mt.get(2).born_near == 1  # type: ignore[union-attr]
    top = mt.update(4 / 30, np.array([[324.0, 226.0, 8.6]]))
    assert top == [1] and mt.primary_id == 1 and [tr.track_id for tr in mt.tracks] == [1]
    tr = mt.get(1)
    assert tr is not None and tr.missed == 0 and tr.hits == 6 and np.allclose(tr.state, [324.0, 226.0, 8.6])
    assert mt.update(5 / 30, np.array([[324.0, 226.0, 8.6]])) == [1]


def test_an_object_begun_apart_never_takes_the_primarys_place() -> None:
    """Another object, first seen outside the primary's gate, passes where the primary is predicted while the
    primary is hidden: it keeps its own id and the primary coasts."""
    mt = _primary_at(250.0)
    mt.update(3 / 30, np.array([[324.0, 250.0, 8.6], [200.0, 250.0, 8.6]]))
    assert mt.get(2) is not None and mt.get(2).born_near is None  # type: ignore[union-attr]
    for k, x in enumerate((240.0, 280.0, 320.0)):
        assert mt.update((4 + k) / 30, np.array([[x, 250.0, 8.6]])) == [2]
    assert mt.primary_id == 1 and mt.get(1).missed == 3  # type: ignore[union-attr]


def _primary_gone_other_seen(hold_s: float | None, seconds: float) -> MultiTracker:
    """The primary (track 1, seen 0.1 s) leaves the view; another object, far from it, is seen for SECONDS
    (confirmed after 2 sightings) at 30 frames a second."""
    mt = MultiTracker(TrackerConfig(primary_hold_s=hold_s))
    for k in range(3):
        mt.update(k / 30, np.array([[324.0, 250.0, 8.6]]))
    frames = round(seconds * 30)
    for k in range(frames):
        assert mt.update((3 + k) / 30, np.array([[50.0, 300.0, 12.0]])) == [2]
    return mt


def test_a_primary_unseen_past_the_hold_yields_to_a_target_in_view() -> None:
    """Live: the primary left the view, the aim gave it up after its loss timeout (1.5 s) and sent the mount
    home, while a newly confirmed target was seen; the primary kept the role, coasting "not detected",
    until max_missed (60 frames). Now the oldest seen confirmed track takes it once the primary has gone
    unseen primary_hold_s."""
    mt = _primary_gone_other_seen(1.5, 1.5)  # unseen since 2/30 s, now 47/30 s: 1.5 s exactly, held
    assert mt.primary_id == 1 and mt.get(1) is not None and mt.get(1).missed == 45  # type: ignore[union-attr]
    mt.update(48 / 30, np.array([[50.0, 300.0, 12.0]]))
    assert mt.primary_id == 2 and mt.get(1) is not None  # the old one lives on (coasting), not primary
    # it is seen again: it stays a track of its own; the role does not come back
    assert mt.update(49 / 30, np.array([[50.0, 300.0, 12.0], [324.0, 250.0, 8.6]])) == [2, 1]
    assert mt.primary_id == 2


def test_a_coasting_primary_keeps_the_role_when_no_other_target_is_seen_or_no_hold_is_set() -> None:
    mt = MultiTracker(TrackerConfig(primary_hold_s=1.5))
    for k in range(3):
        mt.update(k / 30, np.array([[324.0, 250.0, 8.6]]))
    for k in range(55):  # 1.8 s unseen, nothing else in view
        mt.update((3 + k) / 30, np.zeros((0, 3)))
    assert mt.primary_id == 1
    mt.update(58 / 30, np.array([[50.0, 300.0, 12.0]]))  # seen once: not confirmed, no primary
    assert mt.primary_id == 1
    kept = _primary_gone_other_seen(None, 1.9)  # never yields: until dropped (max_missed 60 frames)
    assert kept.primary_id == 1
    dropped = _primary_gone_other_seen(None, 2.1)
    assert dropped.get(1) is None and dropped.primary_id == 2
