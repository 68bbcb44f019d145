"""A background level with a far target by its track's recent disparities still hides the target's bottom
when this frame's disparity jumps nearer (tracker.visibility.cuts level_from, Pipeline._level_from): a far
walker's head and shoulders over a hedge lost its "hidden below" term for a frame and was placed 11 px off
with a 1-σ of 0.4 px (endless:body frame 913)."""

from __future__ import annotations

import numpy as np

from tracker.pipeline import Pipeline
from tracker.results import Blob
from tracker.sim.rig import default_rig
from tracker.visibility import VisibilityConfig, cuts

SIZE = (640, 480)


def _head_over_hedge() -> tuple[np.ndarray, tuple[int, int, int, int], np.ndarray, np.ndarray]:
    """A 14 x 12 px head and shoulders whose lower part a hedge at 7.06 px hides; a far wall (3 px) above."""
    box = (240, 228, 284, 266)
    mask = np.zeros((box[3] - box[1], box[2] - box[0]), bool)
    mask[4:16, 15:29] = True
    bg = np.full(mask.shape, 3.0, np.float32)
    bg[16:] = 7.06
    return mask, box, bg, np.ones(mask.shape, bool)


def test_the_level_test_starts_from_the_tracks_disparity_where_that_is_farther() -> None:
    mask, box, bg, valid = _head_over_hedge()
    cfg = VisibilityConfig()
    assert cuts(mask, box, SIZE, 7.3, bg, valid, cfg).bottom_by_background  # level within 0.5 px
    jumped = cuts(mask, box, SIZE, 7.7, bg, valid, cfg)  # the frame's disparity 0.4 px nearer
    assert not jumped.bottom_by_background and not jumped.sides[3]
    held = cuts(mask, box, SIZE, 7.7, bg, valid, cfg, level_from=7.35)
    assert held.bottom_by_background and held.sides[3]
    assert not cuts(mask, box, SIZE, 7.7, bg - 1.0, valid, cfg, level_from=7.35).bottom_by_background  # behind


def test_level_from_is_the_median_of_the_tracks_stereo_sightings_when_farther_than_the_blob() -> None:
    pipe = Pipeline(default_rig(SIZE))
    obs = [7.31, 7.36, 7.40, 7.66]
    for k, d in enumerate(obs):
        (track_id,) = pipe.tracker.update(k / 30.0, np.array([[260.0, 240.0, d]]), np.array([0.1]))
    mask, box, _, _ = _head_over_hedge()

    def blob(d: float) -> Blob:
        c = np.array([262.0, 238.0])
        return Blob(box, mask, int(mask.sum()), c, c, d, 0.1, 3.0, 0.9)

    assert pipe._level_from(blob(7.66), track_id) == float(np.median(obs))
    assert pipe._level_from(blob(7.30), track_id) is None  # the blob's own disparity is the farther
    assert pipe._level_from(blob(7.66), None) is None and pipe._level_from(blob(7.66), 999) is None
