"""Frames lost at start-up when a target stands in view from frame 0 (issue 12 item 4; `tmeye eval --startup`).

The scenario: a person-sized target stands 8 m away, in front of the simulated backdrop, for the first
1.5 s, then walks left and right (±2 m, period 8 s), crossing the place where it stood every 4 s. The
pipeline learns its background from frame 0 (no empty scene) in one of three ways: `first-frame` (the
first pair taken as the empty background, the real sources' old method), `stream` (the first pair, then
the stream's robust statistics: tracker.bglearn) and, for reference, `survey` (an empty-scene pair, what
the simulator's surveys give). A frame is lost when the target is visible to both cameras and no
detection lies on it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from tracker.evaluation import _Acc, score_frame
from tracker.pipeline import Pipeline
from tracker.sim.scenarios import TWO_PI, Scenario, SimRig

F64 = NDArray[np.float64]
METHODS = ("first-frame", "stream", "survey")
STAND_S = 1.5


def _stand_then_walk(t: float) -> F64:
    """Stands at x = 0, 8 m away, for STAND_S seconds, then walks ±2 m left and right every 8 s."""
    x = 0.0 if t < STAND_S else 2.0 * np.sin(TWO_PI * (t - STAND_S) / 8.0)
    return np.array([x, 1.5 - 0.85, 8.0])


STARTUP = Scenario("startup", "a person stands in view from frame 0 for 1.5 s, then walks ±2 m at 8 m, cameras "
                   "still", frames=360, paths=((1, _stand_then_walk),), person=True)


@dataclass(frozen=True)
class StartupReport:
    """One method: visible frames, frames lost (all, in the first `early_s` seconds, after the target
    started to walk), first frame detected after it started to walk, false-target frames, relearns."""

    method: str
    frames: int
    visible_frames: int
    lost_frames: int
    lost_first_4s: int
    lost_walking: int
    first_detected_walking: int | None
    false_target_frames: int
    relearns: int

    def to_json(self) -> dict[str, object]:
        return dict(self.__dict__)


def run_startup(method: str, frames: int | None = None, seed: int = 0) -> StartupReport:
    """Run the start-up scenario with one background method (METHODS) and count the frames lost."""
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; known: {', '.join(METHODS)}")
    sim = SimRig(STARTUP, seed=seed)
    pipe = Pipeline(sim.rig)
    first = sim.step().frame  # frame 0: the target stands in it
    if method == "survey":
        pipe.learn_background(sim.background())
    elif method == "stream":
        pipe.learn_background_from_stream(first)
    else:
        pipe.learn_background(first)
    n = min(frames or STARTUP.frames, STARTUP.frames)
    acc = _Acc()
    lost = lost_early = lost_walking = 0
    first_walking: int | None = None
    for i in range(1, n):
        sf = sim.step()
        res = pipe.step(sf.frame)
        seen, got = acc.visible, acc.detected
        score_frame(acc, res, sf.truth, pipe, pipe.subtractor.cfg.min_area_px)
        if acc.visible == seen:
            continue
        walking = i / STARTUP.fps >= STAND_S
        if acc.detected > got:
            if walking and first_walking is None:
                first_walking = i
            continue
        lost += 1
        lost_early += i / STARTUP.fps < 4.0
        lost_walking += walking
    relearns = pipe.learner.relearns if pipe.learner is not None else 0
    return StartupReport(method, n, acc.visible, lost, lost_early, lost_walking, first_walking, acc.false_target,
                         relearns)
