"""Running a simulated scenario through the pipeline in tests."""

from __future__ import annotations

from tracker.evaluation import target_prior
from tracker.pipeline import Pipeline
from tracker.results import FrameResult
from tracker.sim.scenarios import SimFrame, SimRig, get_scenario


def run_frames(name: str, frames: int) -> tuple[Pipeline, SimFrame, FrameResult]:
    """A scenario's first `frames` frames through a pipeline with the scenario's solid prior, its
    background learnt from the empty scene: the pipeline, the last frame and its result."""
    scenario = get_scenario(name)
    sim = SimRig(scenario)
    pipe = Pipeline(sim.rig, solid=target_prior(scenario))
    pipe.learn_background(sim.background())
    for _ in range(frames):
        sf = sim.step()
        res = pipe.step(sf.frame)
    return pipe, sf, res
