"""Two cameras whose exposures part (issue 12: real cameras; `tmeye eval --exposure`).

Real cameras each expose on their own: when one re-exposes, the ratio of their greys steps. pan:body (the
cameras pan and tilt, so eq. (9) alone finds objects) and walk:body (cameras still, the temporal model
draws the outlines) run with the right camera's exposure stepped to `RATIOS` times the left's 2 s into the
run, each with the reference image's exposure matched to the key's (tracker.exposure, as the tracker
runs) and without, beside the same scene with the cameras alike; and pan:body with the right camera at
0.8 from the start, so that the survey's pairs differ too (the background is learnt from them matched,
tracker.pipeline). For each: the tracker's figures
(tracker.evaluation), the median ratio k measured after the step, and the frames the reference image was
scaled in.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from tracker.evaluation import _Acc, _report, score_frame, survey_poses, target_prior, timed_step
from tracker.exposure import ExposureBalance, ExposureConfig
from tracker.pipeline import Pipeline
from tracker.sim.scenarios import SimRig, get_scenario

SCENES = ("pan:body", "walk:body")
RATIOS = (0.8, 1.2)
_KEYS = ("visible_frames", "detection_rate", "false_target_frames", "id_switches", "pixel_f1", "range_rmse_m",
         "azimuth_rmse_deg", "elevation_rmse_deg", "range_nees")


@dataclass(frozen=True)
class ExposureStep:
    """The right camera's exposure over the left's at scene time t (s): `ratio` from `at_s` on, 1 before."""

    ratio: float
    at_s: float = 2.0

    def __call__(self, t: float) -> float:
        return self.ratio if t >= self.at_s else 1.0


def run_exposure(scene: str, ratio: float, matched: bool = True, at_s: float = 2.0, seed: int = 0,
                 frames: int | None = None) -> dict[str, object]:
    """One run of `scene` with the right camera's exposure stepped to `ratio` at `at_s` (s); matched: the
    tracker matches the exposures (its default), else it compares the images as they come."""
    scenario = replace(get_scenario(scene), right_gain=ExposureStep(ratio, at_s))
    sim = SimRig(scenario, seed=seed)
    pipe = Pipeline(sim.rig, solid=target_prior(scenario))
    if not matched:
        pipe.subtractor.exposure = ExposureBalance(ExposureConfig(dead_band=math.inf))
    for g in survey_poses(scenario):
        pipe.learn_background(sim.background(g))
    n = min(frames or scenario.frames, scenario.frames)
    acc, ks, applied = _Acc(), [], 0
    for _ in range(n):
        sf, res = timed_step(acc, sim, pipe)
        score_frame(acc, res, sf.truth, pipe, pipe.subtractor.cfg.min_area_px)
        last = pipe.subtractor.exposure.last
        applied += int(last.applied)
        if sf.truth.t >= at_s:
            ks.append(last.k)
    rep = _report(scenario.name, seed, n, acc, scenario.gain, scenario.fps).to_json()
    out: dict[str, object] = {k: rep[k] for k in _KEYS}
    out["k_median_after_step"] = round(float(np.median(ks)), 4) if ks else None
    out["scaled_frames"] = applied
    return out


def exposure_table(seed: int = 0, frames: int | None = None) -> dict[str, object]:
    """Every scene: the cameras alike, then each ratio matched and without: {"pan:body right x1": {...},
    "pan:body right x0.8": {"matched": {...}, "without": {...}}, ...}; and pan:body with the right camera
    at 0.8 from the start, the survey's pairs too ("pan:body right x0.8 from the start")."""
    out: dict[str, object] = {}
    for scene in SCENES:
        out[f"{scene} right x1"] = run_exposure(scene, 1.0, seed=seed, frames=frames)
        for ratio in RATIOS:
            out[f"{scene} right x{ratio:g}"] = {
                "matched": run_exposure(scene, ratio, True, seed=seed, frames=frames),
                "without": run_exposure(scene, ratio, False, seed=seed, frames=frames)}
    out["pan:body right x0.8 from the start"] = {
        "matched": run_exposure("pan:body", 0.8, True, at_s=0.0, seed=seed, frames=frames),
        "without": run_exposure("pan:body", 0.8, False, at_s=0.0, seed=seed, frames=frames)}
    return out
