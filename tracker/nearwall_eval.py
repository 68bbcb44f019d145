"""Targets close to their background (issue 12 item 3; `tmeye eval --near-wall`).

A person-sized target (0.5 x 1.7 m) walks left and right in front of a textured wall at 7 m, the gap
between the wall and the farthest edge of its board 0.05, 0.1, 0.2 or 0.5 m, cameras still; it enters
3 s into the run (the temporal model first learns the wall). A fifth run repeats 0.1 m with the
`illumination` scenario's light steps and ramps. OpenCV's MOG2 (default settings, no shadow detection,
30 empty frames first) runs on the same left images: a frame counts as detected by MOG2 when its
foreground covers at least half of the target's pixels (MOG2 gives no range).
"""

from __future__ import annotations

import cv2
import numpy as np

from tracker.evaluation import _Acc, _f1, _report, score_frame, survey_poses, timed_step
from tracker.pipeline import Pipeline
from tracker.sim.scenarios import SimRig, near_wall_scenario

GAPS_M = (0.05, 0.1, 0.2, 0.5)
_KEYS = ("visible_frames", "detection_rate", "false_target_frames", "pixel_f1", "range_rmse_m", "range_bias_pct",
         "range_limit_m", "azimuth_rmse_deg", "step_ms_median")


def run_near_wall(gap_m: float, light: bool = False, seed: int = 0, frames: int | None = None) -> dict[str, object]:
    """One gap: the tracker's figures (tracker.evaluation) and MOG2's on the same frames."""
    scenario = near_wall_scenario(gap_m, light=light)
    sim = SimRig(scenario, seed=seed)
    pipe = Pipeline(sim.rig)
    for g in survey_poses(scenario):
        pipe.learn_background(sim.background(g))
    mog = cv2.createBackgroundSubtractorMOG2(detectShadows=False)
    empty = sim.background().left
    for _ in range(30):
        mog.apply(empty)
    n = min(frames or scenario.frames, scenario.frames)
    acc = _Acc()
    mog_hits = mog_visible = 0
    tp = fp = fn = 0
    for _ in range(n):
        sf, res = timed_step(acc, sim, pipe)
        seen = acc.visible
        score_frame(acc, res, sf.truth, pipe, pipe.subtractor.cfg.min_area_px)
        truth = sf.truth.ids_left == 1
        fg = mog.apply(sf.frame.left) > 0
        tp, fp = tp + int(np.count_nonzero(fg & truth)), fp + int(np.count_nonzero(fg & ~truth))
        fn += int(np.count_nonzero(~fg & truth))
        if acc.visible > seen:
            mog_visible += 1
            mog_hits += int(np.count_nonzero(fg & truth)) >= 0.5 * int(np.count_nonzero(truth))
    rep = _report(scenario.name, seed, n, acc, scenario.gain, scenario.fps).to_json()
    out: dict[str, object] = {"gap_m": gap_m, "light_steps": light}
    out.update({k: rep[k] for k in _KEYS})
    out["mog2_detection_rate"] = round(mog_hits / max(mog_visible, 1), 6)
    out["mog2_pixel_f1"] = round(_f1(tp, fp, fn), 6)
    return out


def near_wall_table(seed: int = 0, frames: int | None = None) -> dict[str, object]:
    """Every gap, then 0.1 m with light steps: {"gap 0.05": {...}, ...}."""
    runs = [(g, False) for g in GAPS_M] + [(0.1, True)]
    return {f"gap {g:g}{' light steps' if light else ''}": run_near_wall(g, light, seed, frames) for g, light in runs}
