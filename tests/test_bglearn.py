"""Learning the background from a stream with a target in view from frame 0 (tracker.bglearn)."""

from __future__ import annotations

import numpy as np
import pytest

from tracker.bglearn import Sighting, StreamLearnConfig, StreamLearner, changed_box, median_u8
from tracker.frames import StereoFrame
from tracker.pipeline import Pipeline
from tracker.sim.scenarios import SimRig
from tracker.startup_eval import STAND_S, STARTUP, run_startup


def test_masked_median_matches_numpy_over_the_valid_samples() -> None:
    rng = np.random.default_rng(0)
    stack = [rng.integers(0, 256, (7, 9), dtype=np.uint8) for _ in range(11)]
    valid = [rng.random((7, 9)) > 0.3 for _ in range(11)]
    valid[0][0, 0] = False
    for v in valid:
        v[1, 1] = False  # never valid: the fallback
    fallback = np.full((7, 9), 77, np.uint8)
    got = median_u8(stack, valid, fallback)
    for y in range(7):
        for x in range(9):
            vals = sorted(int(s[y, x]) for s, v in zip(stack, valid, strict=True) if v[y, x])
            assert got[y, x] == (vals[(len(vals) - 1) // 2] if vals else 77)


def _frame(i: int, left: np.ndarray, right: np.ndarray) -> StereoFrame:
    return StereoFrame(i, left, right, i / 30.0, i / 30.0)


def test_learner_ignores_a_passing_object_the_light_and_tracked_pixels() -> None:
    rng = np.random.default_rng(2)
    bg = rng.integers(40, 160, (48, 64), dtype=np.uint8)
    learner = StreamLearner(_frame(0, bg, bg), StreamLearnConfig(sample_every=1, window=9, first_after=9, bands=3))
    out = None
    for i in range(1, 16):  # 9 samples, then 3 bands and the result, one frame each
        gain = 1.3 if i % 2 else 1.0
        img = np.clip(bg * gain, 0, 255).astype(np.uint8)
        img[10:20, (i * 5) % 50:(i * 5) % 50 + 8] = 250  # a passing object, never found by the tracker
        mask = np.ones((6, 6), bool)
        img[30:36, 30:36] = 5  # a tracked object standing still: left out of the samples
        seen = [Sighting((30, 30, 36, 36), mask, 0.0)]
        got = learner.observe(_frame(i, img, img), gain, True, seen)
        out = got or out
    assert out is not None and learner.relearns == 1
    assert np.abs(out.left.astype(int) - bg).max() <= 1  # the background, at gain 1
    assert np.abs(out.right.astype(int) - bg).max() <= 1
    assert out.left_dev[30:36, 30:36].max() < 1.0


def test_changed_box_bounds_what_differs() -> None:
    a = np.full((100, 120), 80, np.uint8)
    b = a.copy()
    b[40:60, 70:90] = 200
    assert changed_box(a, b, 12, 16, grow=0) == (70, 40, 90, 60)
    assert changed_box(a, a, 12, 16) is None


def test_a_target_standing_at_frame_0_is_out_of_the_background_once_it_walked_away() -> None:
    sim = SimRig(STARTUP)
    pipe = Pipeline(sim.rig)
    first = sim.step().frame
    pipe.learn_background_from_stream(first)
    box = (305, 230, 335, 350)  # where the person stood (8 m: about 22 px of disparity)
    surveyed = Pipeline(sim.rig)
    surveyed.learn_background(sim.background())
    truth = float(np.median(surveyed.subtractor.correspondence(0, None, box).disparity))
    before = float(np.median(pipe.subtractor.correspondence(0, None, box).disparity))
    for _ in range(130):  # the person walks off at 1.5 s; relearns at about 1.6 s and 4.3 s
        pipe.step(sim.step().frame)
    after = float(np.median(pipe.subtractor.correspondence(0, None, box).disparity))
    assert truth < 12.0 and before > 20.0  # the person, taken for background
    assert after == pytest.approx(truth, abs=1.0)  # what is behind it, as an empty-scene survey sees it


def test_a_target_in_view_from_frame_0_is_detected_as_soon_as_it_walks() -> None:
    rep = run_startup("stream", frames=60)
    assert rep.first_detected_walking is not None
    assert rep.first_detected_walking <= STAND_S * STARTUP.fps + 3
    assert rep.false_target_frames == 0
