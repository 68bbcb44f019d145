from __future__ import annotations

import time

import numpy as np
import pytest

from tracker.detect import DetectorConfig
from tracker.evaluation import run_scenario
from tracker.frames import FrameError, StereoFrame
from tracker.pipeline import Pipeline
from tracker.sim.scenarios import SimRig, get_scenario


def _pipeline(name: str, seed: int = 0) -> tuple[SimRig, Pipeline]:
    sim = SimRig(get_scenario(name), seed=seed)
    pipe = Pipeline(sim.rig)
    pipe.learn_background(sim.background())
    return sim, pipe


def test_each_stage_against_ground_truth() -> None:
    sim, pipe = _pipeline("walk")
    checked = 0
    for i in range(40):
        sf = sim.step()
        res = pipe.step(sf.frame)
        tt = sf.truth.target(1)
        assert tt is not None and tt.centroid_left is not None
        if i == 0:
            assert res.primary is None  # a track is confirmed on its second sighting
            continue
        assert res.primary is not None and len(res.detections) == 1
        blob, loc = res.primary.blob, res.primary.loc
        truth_mask = sf.truth.ids_left == 1
        fg = res.foreground_mask(truth_mask.shape)
        f1 = 2 * (fg & truth_mask).sum() / (fg.sum() + truth_mask.sum())
        assert f1 > 0.97  # detection (eq. 9)
        assert np.hypot(*(blob.centroid_raw - tt.centroid_left)) < 0.2  # centroid (eq. 10)
        _, _, d_true = pipe.rect.rig_to_rect(tt.rig[None, :])
        assert blob.disparity == pytest.approx(float(d_true[0]), abs=0.15)  # matching
        assert loc.r == pytest.approx(float(np.linalg.norm(tt.world)), rel=0.01)  # eq. (2)
        assert abs(loc.theta - np.arctan2(tt.world[0], tt.world[2])) < np.radians(0.05)
        assert loc.sigma_r > 0 and loc.sigma_theta > 0 and loc.sigma_phi > 0
        checked += 1
    assert checked == 39


def test_a_track_predicted_past_infinity_is_verified_as_a_new_object() -> None:
    """A track whose disparity falls fast is predicted at a disparity below 0 (a live server's frame
    failed with "d0 must be finite and >= 0, got -4.2"): that prediction narrows no search."""
    sim, pipe = _pipeline("walk")
    for _ in range(5):
        res = pipe.step(sim.step().frame)
    assert res.primary is not None
    x, y = res.primary.blob.centroid_raw
    pipe.tracker.predictions = lambda t: np.array([[x, y, -4.2], [x, y, np.nan]])  # type: ignore[method-assign]
    res = pipe.step(sim.step().frame)
    assert len(res.detections) == 1


def test_lighting_step_does_not_create_or_lose_targets() -> None:
    sim, pipe = _pipeline("illumination")
    for _ in range(70):  # through the 1.0 -> 1.3 step at frame 60
        sf = sim.step()
        res = pipe.step(sf.frame)
    assert len(res.detections) == 1 and res.primary is not None
    tt = sf.truth.target(1)
    assert tt is not None and tt.centroid_left is not None
    assert np.hypot(*(res.primary.blob.centroid_raw - tt.centroid_left)) < 0.5


def test_two_targets_keep_their_identities() -> None:
    sim, pipe = _pipeline("two-targets")
    owner: dict[int, int] = {}
    for _ in range(60):
        sf = sim.step()
        res = pipe.step(sf.frame)
        for det in res.detections:
            c = det.blob.centroid_raw
            truth = min((t for t in sf.truth.targets if t.centroid_left is not None),
                        key=lambda t: float(np.hypot(*(c - t.centroid_left))))
            owner.setdefault(det.track_id, truth.target_id)
            assert owner[det.track_id] == truth.target_id
    assert sorted(owner.values()) == [1, 2]


def test_empty_scene_gives_no_target() -> None:
    sim, pipe = _pipeline("walk")
    for _ in range(5):
        res = pipe.step(sim.background())
        assert res.detections == () and res.primary is None


def test_bad_frames_are_rejected_with_a_reason() -> None:
    sim, pipe = _pipeline("walk")
    good = sim.step().frame
    empty = np.zeros((0, 0), np.uint8)
    with pytest.raises(FrameError, match="left image is empty"):
        pipe.step(StereoFrame(0, empty, good.right, 0.0, 0.0))
    with pytest.raises(FrameError, match="differ in size"):
        pipe.step(StereoFrame(0, good.left, good.right[:-2], 0.0, 0.0))
    with pytest.raises(FrameError, match="grey uint8"):
        pipe.step(StereoFrame(0, good.left.astype(np.float32), good.right, 0.0, 0.0))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="does not match the rig"):
        pipe.step(StereoFrame(0, good.left[:240, :320].copy(), good.right[:240, :320].copy(), 0.0, 0.0))
    assert pipe.step(good).detections  # still works after the bad input


def test_detector_config_validation() -> None:
    with pytest.raises(ValueError, match="epsilon"):
        DetectorConfig(epsilon=0)
    with pytest.raises(ValueError, match="stride"):
        DetectorConfig(stride=3)


def test_short_evaluation_reports_every_field() -> None:
    rep = run_scenario("approach", frames=30).to_json()
    for k in ("frames", "detection_rate", "false_target_frames", "pixel_f1", "centroid_rmse_px",
              "disparity_rmse_px", "range_rmse_m", "range_bias_pct", "range_limit_m", "azimuth_rmse_deg",
              "elevation_rmse_deg"):
        assert k in rep
    assert rep["frames"] == 30 and rep["false_target_frames"] == 0
    assert float(rep["detection_rate"]) > 0.95  # type: ignore[arg-type]


def test_a_new_object_left_out_by_the_budget_is_found_between_frames_and_verified_by_the_next() -> None:
    """With no time at all in the frame for untracked boxes (budget 0), the search for a new object
    waits for `between_frames`; the next frame verifies what it found from its position and disparity.
    Searches not made between frames (never called, or no time left) are made by the next frame itself."""
    sims = [SimRig(get_scenario("walk"), seed=0) for _ in range(4)]
    pipes = [Pipeline(sims[0].rig)] + [Pipeline(sim.rig, verify_budget_ms=0.0, sigma_budget_ms=0.0,
                                                between_frames=True) for sim in sims[1:]]
    for sim, pipe in zip(sims, pipes, strict=True):
        pipe.learn_background(sim.background())
    seen: list[list[int]] = [[], [], [], []]
    left: list[list[int]] = [[], [], [], []]  # searches each frame left for between frames
    for i in range(6):
        frames = [sim.step().frame for sim in sims]
        res = [pipe.step(f) for pipe, f in zip(pipes, frames, strict=True)]
        for k, pipe in enumerate(pipes):
            left[k].append(len(pipe.schedule._later))
        pipes[1].between_frames(time.perf_counter() + 60.0)
        pipes[3].between_frames(time.perf_counter())  # no time: nothing is searched, the next frame does it
        for k, r in enumerate(res):
            if r.detections:
                seen[k].append(i)
        if len(res[1].detections) == 1 and len(res[0].detections) == 1:
            a, b = res[0].detections[0].blob, res[1].detections[0].blob
            assert np.hypot(*(a.centroid_raw - b.centroid_raw)) < 0.05 and abs(a.disparity - b.disparity) < 0.02
            assert pipes[1].sigma_schedule.refreshed >= i - 1  # the 1-σ terms too, once tracked
    assert seen[0] == [0, 1, 2, 3, 4, 5]  # without a budget: found at once
    assert seen[1] == [1, 2, 3, 4, 5] and left[1][:2] == [1, 0]  # searched between frames 0 and 1
    assert seen[2] == seen[3] == [1, 2, 3, 4, 5]  # searched in frame 1, the search left by frame 0 not made
    assert left[2][:2] == left[3][:2] == [1, 0]
    assert pipes[1].sigma_schedule.refreshed >= 3 and pipes[2].sigma_schedule.refreshed == 0
