"""Timing of the per-frame pipeline (`tmeye bench`): each stage and the whole step on one thread, and
OpenCV's MOG2 on both images of the same frames for comparison; and the capture-to-command latency of the
closed loop (tracker.closedloop.ServoLoop: pipeline step + IMM update and prediction + aim step + driver
command call) on the same frames, driving a SimulatedGimbal (its modelled latency is simulated time and
not part of the figure)."""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass

import cv2
import numpy as np

from tracker.aim import AimConfig, AimController
from tracker.closedloop import LoopConfig, ServoLoop
from tracker.frames import StereoFrame
from tracker.pipeline import STAGES, Pipeline
from tracker.sim.scenarios import SimRig, get_scenario


@dataclass(frozen=True)
class BenchReport:
    """Milliseconds per stereo frame (medians unless named _p99)."""

    size: tuple[int, int]
    frames: int
    stage_ms: dict[str, float]
    step_ms_median: float
    step_ms_p99: float
    mog2_pair_ms_median: float
    ratio_vs_mog2: float
    render_ms_median: float
    latency_ms_median: float
    latency_ms_p99: float
    control_ms_median: float
    control_ms_p99: float

    def to_json(self) -> dict[str, object]:
        d = asdict(self)
        d["size"] = f"{self.size[0]}x{self.size[1]}"
        return {k: (round(v, 4) if isinstance(v, float) else v) for k, v in d.items()}


def run_bench(size: tuple[int, int] = (640, 480), frames: int = 300, scenario: str = "walk",
              seed: int = 0) -> BenchReport:
    """Render `frames` frames of a scenario first, then time the pipeline (inside the closed loop) and MOG2
    on them. latency_ms_*: capture to command issued; control_ms_*: the part after the pipeline step."""
    from tracker.closedloop_eval import closed_loop_imm
    from tracker.servo.sim import SimulatedGimbal

    cv2.setNumThreads(1)
    sim = SimRig(get_scenario(scenario), seed=seed, size=size)
    pipe = Pipeline(sim.rig)
    pipe.learn_background(sim.background())
    loop = ServoLoop(pipe, AimController(AimConfig(frame_width_px=size[0], focal_px=pipe.rect.f)),
                     closed_loop_imm(), SimulatedGimbal(), LoopConfig())
    rendered: list[StereoFrame] = []
    render_ms = []
    for _ in range(min(frames, sim.scenario.frames)):
        t0 = time.perf_counter()
        rendered.append(sim.step().frame)
        render_ms.append((time.perf_counter() - t0) * 1e3)
    mogs = (cv2.createBackgroundSubtractorMOG2(), cv2.createBackgroundSubtractorMOG2())
    bg = sim.background()
    for _ in range(5):
        mogs[0].apply(bg.left)
        mogs[1].apply(bg.right)
    # one after the other, each on its own (interleaving them would let MOG2's 30 MB model evict the
    # tracker's tables from the cache every frame, which no deployment does)
    steps: list[float] = []
    mog_ms: list[float] = []
    latency: list[float] = []
    stages: dict[str, list[float]] = {s: [] for s in STAGES}
    for f in rendered:
        st = loop.step(f)
        steps.append(st.pipeline_ms)
        latency.append(st.latency_ms)
        for s in STAGES:
            stages[s].append(st.result.stage_ms[s])
    for f in rendered:
        t1 = time.perf_counter()
        mogs[0].apply(f.left)
        mogs[1].apply(f.right)
        mog_ms.append((time.perf_counter() - t1) * 1e3)
    control = [a - b for a, b in zip(latency, steps, strict=True)]
    step_med = float(np.median(steps))
    mog_med = float(np.median(mog_ms))
    return BenchReport(size, len(rendered), {s: float(np.median(v)) for s, v in stages.items()},
                       step_med, float(np.percentile(steps, 99)), mog_med, mog_med / step_med,
                       float(np.median(render_ms)), float(np.median(latency)), float(np.percentile(latency, 99)),
                       float(np.median(control)), float(np.percentile(control, 99)))
