"""The left temporal model B, D is not learnt under the stereo stage's candidate cells (tracker.detect): an
object no stage verified yet (a target edging in at the image border) must not become background."""

from __future__ import annotations

import numpy as np

from tracker.frames import StereoFrame
from tracker.pipeline import Pipeline
from tracker.sim.scenarios import SimRig, get_scenario


def _still_pipeline() -> tuple[Pipeline, StereoFrame]:
    sim = SimRig(get_scenario("walk"), seed=0)
    pipe = Pipeline(sim.rig)
    empty = sim.background()
    pipe.learn_background(empty)
    pipe.subtractor.step(empty)  # the first frame at the pose: seeds the floor and the maps
    return pipe, empty


def test_b_and_d_are_held_under_unverified_candidate_cells_and_learnt_elsewhere() -> None:
    pipe, empty = _still_pipeline()
    sub = pipe.subtractor
    left = empty.left.copy()
    left[200:260, 620:640] = np.where(left[200:260, 620:640] > 128, 20, 235)  # a strip at the right border
    frame = StereoFrame(empty.index + 1, left, empty.right, empty.t_left, empty.t_right, empty.gimbal)
    cands = sub.step(frame)
    assert cands.boxes  # the stereo residual sees the strip
    model = sub.left_background(frame.gimbal)
    assert model is not None
    before = model[0].copy()
    for _ in range(24):  # every stripe once, with no verified object
        sub.update_left_background(frame, [], 1.0)
    bg = sub.left_background(frame.gimbal)
    assert bg is not None
    assert np.array_equal(bg[0][200:260, 620:640], before[200:260, 620:640])  # the strip is not learnt
    far = np.abs(left[20:60, 20:200].astype(np.float32) - bg[0][20:60, 20:200])
    assert float(far.max()) < 1e-3 + float(np.abs(left[20:60, 20:200].astype(np.float32)
                                                   - before[20:60, 20:200]).max())  # elsewhere B learns


def test_without_candidates_nothing_is_held() -> None:
    pipe, empty = _still_pipeline()
    sub = pipe.subtractor
    sub.step(empty)
    assert sub._held_rows(0, 20, 640) is None
