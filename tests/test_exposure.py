"""The reference camera's exposure matched to the key camera's before eq. (9) (tracker.exposure), the
simulator's per-camera exposure, and `tmeye eval --exposure`'s arguments."""

from __future__ import annotations

import math
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest

from tracker.exposure import ExposureBalance, ExposureConfig
from tracker.exposure_eval import ExposureStep, run_exposure
from tracker.pipeline import Pipeline
from tracker.sim.scenarios import SimRig, get_scenario

U8 = np.uint8


def _scene(k: float, outliers: float = 0.0, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A textured reference grid (120, 160), the key camera's view of it k times as bright, a share of
    `outliers` samples replaced by an object's greys, and every sample valid."""
    rng = np.random.default_rng(seed)
    ref = rng.integers(30, 180, (120, 160)).astype(U8)
    key = np.clip(np.rint(ref * k), 0, 255).astype(U8)
    obj = rng.random(ref.shape) < outliers
    key[obj] = rng.integers(0, 256, int(obj.sum())).astype(U8)
    return key, ref, np.full(ref.shape, 255, U8)


def test_the_ratio_is_measured_past_an_object_and_applied() -> None:
    bal = ExposureBalance()
    r = bal.step(*_scene(1.25, outliers=0.3))
    assert r.applied and r.k == pytest.approx(1.25, abs=0.01) and r.samples > 10_000
    right = np.full((4, 4), 100, U8)
    assert (ExposureBalance.balanced(right, r) == round(100 * r.k)).all()


def test_cameras_alike_are_left_as_they_are() -> None:
    bal = ExposureBalance()
    r = bal.step(*_scene(1.01))
    assert not r.applied and r.k == pytest.approx(1.01, abs=0.005)
    right = np.zeros((4, 4), U8)
    assert ExposureBalance.balanced(right, r) is right


def test_too_few_usable_samples_keep_the_last_ratio() -> None:
    key, ref, valid = _scene(1.3)
    valid[:, :] = 0
    valid[:10, :10] = 255  # 100 valid samples
    r = ExposureBalance().step(key, ref, valid)
    assert (r.k, r.applied, r.samples) == (1.0, False, 100)  # none measured before
    sat = np.full((120, 160), 250, U8)  # saturated in both: unusable
    assert not ExposureBalance().step(np.full_like(sat, 255), sat, np.full_like(sat, 255)).applied
    bal = ExposureBalance()
    first = bal.step(*_scene(1.25))
    covered = bal.step(key, ref, valid)  # a view mostly covered: the ratio measured before stands
    assert covered.applied and covered.k == first.k and covered.samples == 100


def test_a_first_guess_from_whole_images() -> None:
    key, ref, _ = _scene(0.8)
    g = ExposureBalance().guessed(key, ref)
    assert g.applied and g.k == pytest.approx(0.8, abs=0.01)
    assert not ExposureBalance().guessed(ref, ref).applied
    dark = np.full((120, 160), 5, U8)
    assert ExposureBalance().guessed(dark, ref).k == 1.0  # a dark view tells nothing


@pytest.mark.parametrize("ratio", [0.8, 1.3])
def test_a_survey_pair_of_unlike_cameras_is_learnt_matched(ratio: float) -> None:
    """The survey pair's exposures differ: the background is learnt from the pair matched, so eq. (9)'s
    floor is as low as with cameras alike; learnt as it comes, the floor holds the difference."""
    def floor(r: float, matched: bool = True) -> float:
        sim = SimRig(replace(get_scenario("walk:plate"), right_gain=ExposureStep(r, 0.0)), seed=0)
        pipe = Pipeline(sim.rig)
        if not matched:
            pipe.subtractor.exposure = ExposureBalance(ExposureConfig(dead_band=math.inf))
        pipe.learn_background(sim.background())
        if matched:
            assert pipe.subtractor.exposure.last.k == pytest.approx(1 / r, abs=0.01)
        return float(pipe.subtractor.maps(None).low.floor.mean())

    alike = floor(1.0)
    assert floor(ratio) < alike + 0.5
    assert floor(ratio, matched=False) > alike + 5.0


def test_bad_settings_are_refused() -> None:
    with pytest.raises(ValueError, match="dead_band"):
        ExposureConfig(dead_band=-0.1)
    with pytest.raises(ValueError, match="lo and hi"):
        ExposureConfig(lo=200, hi=100)


def test_the_simulator_exposes_the_right_camera_on_its_own() -> None:
    base = get_scenario("walk:plate")
    alike = SimRig(base, seed=3).step().frame
    brighter = SimRig(replace(base, right_gain=ExposureStep(1.2, at_s=0.0)), seed=3).step().frame
    assert np.array_equal(alike.left, brighter.left)
    mid = (alike.right > 40) & (alike.right < 180)
    ratio = float(np.median(brighter.right[mid].astype(float) / alike.right[mid]))
    assert ratio == pytest.approx(1.2, abs=0.02)


def test_a_camera_re_exposing_while_the_mount_pans_loses_nothing() -> None:
    """pan:body, the right camera's exposure stepped to 1.2 times the left's at 0.5 s (frame 15): with the
    exposures matched every frame keeps its target; compared as they come, eq. (9) sees every background
    pixel change and the target is lost from the step on."""
    matched = run_exposure("pan:body", 1.2, True, at_s=0.5, frames=40)
    assert matched["detection_rate"] == 1.0 and matched["false_target_frames"] == 0
    assert matched["k_median_after_step"] == pytest.approx(1 / 1.2, abs=0.01) and matched["scaled_frames"] == 25
    without = run_exposure("pan:body", 1.2, False, at_s=0.5, frames=40)
    assert without["scaled_frames"] == 0
    assert isinstance(without["detection_rate"], float) and without["detection_rate"] < 0.5


@pytest.mark.parametrize("extra", [["--startup"], ["--scenario", "walk"], ["--all"]])
def test_eval_exposure_takes_no_other_scene(extra: list[str]) -> None:
    out = subprocess.run([sys.executable, "-m", "tmeye", "eval", "--exposure", *extra], capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "--exposure" in lines[0]
