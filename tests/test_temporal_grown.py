"""A tracked object the temporal stage finds (eq. 9 seeing little of it: a walker before a low wall at its own
depth) has its outline grown into the changed pixels that are its surface too, as the stereo stage's
tracked outlines are (tracker.temporal.TemporalDetector._grown, tracker.growth.grow_tracked)."""

from __future__ import annotations

import pytest
from sim_helpers import walker_errors

import tracker.temporal as temporal


def test_a_walkers_legs_the_temporal_model_saw_apart_join_its_outline(monkeypatch: pytest.MonkeyPatch) -> None:
    # endless:body frame 1325: the temporal outline kept the walker's body and upper legs (its largest
    # region), 9.3 px from the truth's centroid; grown, 4.5 px when measured
    got = walker_errors("endless:body", 1325)
    assert len(got) == 1 and got[0] < 6.5
    monkeypatch.setattr(temporal.TemporalDetector, "_grown", lambda self, frame, box, b, model, changed: b)
    got = walker_errors("endless:body", 1325)
    assert len(got) == 1 and got[0] > 8.0
