"""Running a simulated scenario through the pipeline in tests."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest

import tracker.rim_recovery as rim_recovery
from tracker.evaluation import _on, survey_poses, target_prior
from tracker.pipeline import Pipeline
from tracker.results import Blob, FrameResult
from tracker.sim.scenarios import SimFrame, SimRig, get_scenario


def each_frame(name: str, frames: int, surveyed: bool = False) -> Iterator[tuple[Pipeline, SimFrame, FrameResult]]:
    """A scenario's first `frames` frames through a pipeline with the scenario's solid prior, its
    background learnt from the empty scene (with `surveyed`, at every pose `tmeye eval` surveys): the
    pipeline, each frame and its result."""
    scenario = get_scenario(name)
    sim = SimRig(scenario)
    pipe = Pipeline(sim.rig, solid=target_prior(scenario))
    for g in survey_poses(scenario) if surveyed else [None]:
        pipe.learn_background(sim.background(g))
    for _ in range(frames):
        sf = sim.step()
        yield pipe, sf, pipe.step(sf.frame)


def run_frames(name: str, frames: int, surveyed: bool = False) -> tuple[Pipeline, SimFrame, FrameResult]:
    """`each_frame`'s last: the pipeline, the last frame and its result."""
    *_, last = each_frame(name, frames, surveyed)
    return last


def walker_errors(name: str, frame: int) -> list[float]:
    """A scenario run to `frame`: the centroid errors (px) of the detections mostly on target 1 there."""
    _, sf, res = run_frames(name, frame + 1)
    tt = sf.truth.target(1)
    assert tt is not None and tt.centroid_left is not None
    return [float(np.hypot(*(d.blob.centroid_raw - tt.centroid_left))) for d in res.detections
            if _on(d, tt, sf.truth.ids_left)]


def box_blob(box: tuple[int, int, int, int], d: float, d_bg: float, part_only: bool = False) -> Blob:
    """A verified blob filling its box (x0, y0, x1, y1) at disparity d before a background at d_bg (px),
    its centroid the box's centre: a stand-in for the objects the pipeline's joining rules take."""
    x0, y0, x1, y1 = box
    mask = np.ones((y1 - y0, x1 - x0), bool)
    c = np.array([(x0 + x1 - 1) / 2, (y0 + y1 - 1) / 2])
    return Blob(box, mask, mask.size, c, c.copy(), d, 0.05, d_bg, 0.95, part_only=part_only)


def outline_in_image(blob: Blob, shape: tuple[int, ...]) -> np.ndarray:
    """A blob's outline as a mask over the whole left image (bool, `shape`)."""
    out = np.zeros(shape, bool)
    x0, y0, x1, y1 = blob.box
    out[y0:y1, x0:x1] = blob.mask
    return out


def without_limbs(monkeypatch: pytest.MonkeyPatch) -> None:
    """The pipeline without the limbs' closing (tracker.limbs), for figures measured before it."""
    monkeypatch.setattr(rim_recovery, "limbs_closed", lambda obj, pictures, allowed: obj)
