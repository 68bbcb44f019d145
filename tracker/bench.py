"""Timing of the per-frame pipeline (`tmeye bench`): each stage and the whole step on one thread, and
OpenCV's MOG2 on both images of the same frames for comparison; and the capture-to-command latency of the
closed loop (tracker.closedloop.ServoLoop: pipeline step + IMM update and prediction + aim step + driver
command call) on the same frames, driving a SimulatedGimbal (its modelled latency is simulated time and
not part of the figure).

The frames of an open-loop scenario are rendered first (`walk` by default: cameras still, the target from
15 m to 3 m; `pan`: the cameras pan and tilt on a schedule). Each measurement runs in `repeats` passes over
the same frames, and each figure is the best of its passes (as timeit does: other work on the machine only
ever adds time): a median from the pass with the lowest median, a 99th percentile from the pass with the
lowest 99th percentile.

The simulator's render of the frames is timed the same way: render_ms_median on one OpenCV thread, as
everything else here, and render_ms_median_opencv_threads with OpenCV's own thread count (opencv_threads,
what the server runs with). Its own helper thread (one camera each) runs in both."""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass

import cv2
import numpy as np

from tracker.aim import AimConfig, AimController
from tracker.closedloop import LoopConfig, ServoLoop
from tracker.evaluation import survey_poses
from tracker.frames import StereoFrame
from tracker.geometry import StereoRig
from tracker.pipeline import STAGES, Pipeline
from tracker.sim.scenarios import SimRig, get_scenario

OPENCV_THREADS = cv2.getNumThreads()  # OpenCV's own choice, before run_bench pins it to one


@dataclass(frozen=True)
class BenchReport:
    """Milliseconds per stereo frame (medians unless named _p99)."""

    scenario: str
    size: tuple[int, int]
    frames: int
    stage_ms: dict[str, float]
    step_ms_median: float
    step_ms_p99: float
    mog2_pair_ms_median: float
    ratio_vs_mog2: float
    render_ms_median: float
    render_ms_median_opencv_threads: float
    opencv_threads: int
    latency_ms_median: float
    latency_ms_p99: float
    control_ms_median: float
    control_ms_p99: float
    edge_samples: int = 1

    def to_json(self) -> dict[str, object]:
        d = asdict(self)
        d["size"] = f"{self.size[0]}x{self.size[1]}"
        return {k: (round(v, 4) if isinstance(v, float) else v) for k, v in d.items()}


def run_bench(size: tuple[int, int] = (640, 480), frames: int = 300, scenario: str = "walk",
              seed: int = 0, repeats: int = 3, edge_samples: int = 1) -> BenchReport:
    """Render `frames` frames of a scenario first, then, each in its own passes over the same frames: the
    pipeline alone (stage and step times), the pipeline inside the servo loop (latency_ms_*: capture to
    command issued; control_ms_*: the part after the pipeline step), and OpenCV's MOG2 on both images.
    Each is timed in `repeats` passes; each figure is the best of its passes. Raises ValueError for a
    closed-loop scenario (its frames depend on the loop: `tmeye eval` runs those). edge_samples: as
    tracker.evaluation.run_scenario's (the render's cost grows with it)."""
    cv2.setNumThreads(1)
    sc = get_scenario(scenario)
    if sc.closed_loop:
        raise ValueError(f"scenario {scenario!r} is closed-loop (its frames depend on the servo loop): "
                         "time it with tmeye eval; tmeye bench takes open-loop scenarios")

    def fresh() -> SimRig:
        return SimRig(sc, seed=seed, size=size, edge_samples=edge_samples)

    sim = fresh()
    backgrounds = [sim.background(g) for g in survey_poses(sc)]
    n = min(frames, sim.scenario.frames)
    rendered, render_ms = _render(sim, n)
    render_runs = [render_ms] + [_render(fresh(), n, keep=False)[1]
                                 for _ in range(repeats - 1)]
    cv2.setNumThreads(OPENCV_THREADS)
    try:
        threaded_runs = [_render(fresh(), n, keep=False)[1] for _ in range(repeats)]
    finally:
        cv2.setNumThreads(1)
    pipe_runs = [_time_pipeline(sim.rig, backgrounds, rendered) for _ in range(repeats)]
    loop_runs = [_time_loop(sim.rig, backgrounds, rendered, size) for _ in range(repeats)]
    mog_runs = [_time_mog2(backgrounds[0], rendered) for _ in range(repeats)]
    stages = min(pipe_runs, key=lambda r: float(np.median(r[0])))[1]
    steps = [r[0] for r in pipe_runs]
    latency = [r[0] for r in loop_runs]
    control = [[a - b for a, b in zip(*r, strict=True)] for r in loop_runs]
    step_med = _best(steps, 50)
    mog_med = _best(mog_runs, 50)
    return BenchReport(scenario, size, len(rendered), {s: float(np.median(v)) for s, v in stages.items()},
                       step_med, _best(steps, 99), mog_med, mog_med / step_med, _best(render_runs, 50),
                       _best(threaded_runs, 50), OPENCV_THREADS,
                       _best(latency, 50), _best(latency, 99), _best(control, 50), _best(control, 99),
                       edge_samples)


def _render(sim: SimRig, n: int, keep: bool = True) -> tuple[list[StereoFrame], list[float]]:
    """The next n frames of sim (kept only with keep), and the milliseconds each took to render. The passes
    that only time the render drop each frame once it is made, as a running tracker does: holding all of
    them (pan: 240 pairs, 150 MB) puts every new frame on fresh pages (pan: 90 to 180 minor page faults a
    frame against 20 to 35), a cost of this harness, not of the render (0.05 to 0.18 ms a frame, pan, on
    the 2-core test machine)."""
    out: list[StereoFrame] = []
    ms: list[float] = []
    for _ in range(n):
        t0 = time.perf_counter()
        frame = sim.step().frame
        ms.append((time.perf_counter() - t0) * 1e3)
        if keep:
            out.append(frame)
    return out, ms


def _best(runs: list[list[float]], q: float) -> float:
    """The lowest q-th percentile over the passes."""
    return min(float(np.percentile(r, q)) for r in runs)


def _pipeline(rig: StereoRig, backgrounds: list[StereoFrame]) -> Pipeline:
    pipe = Pipeline(rig)
    for b in backgrounds:
        pipe.learn_background(b)
    return pipe


def _time_pipeline(rig: StereoRig, backgrounds: list[StereoFrame], frames: list[StereoFrame]
                   ) -> tuple[list[float], dict[str, list[float]]]:
    """Whole-step and per-stage times (ms) of a fresh pipeline over the frames."""
    pipe = _pipeline(rig, backgrounds)
    steps: list[float] = []
    stages: dict[str, list[float]] = {s: [] for s in STAGES}
    for f in frames:
        t0 = time.perf_counter()
        res = pipe.step(f)
        steps.append((time.perf_counter() - t0) * 1e3)
        for s in STAGES:
            stages[s].append(res.stage_ms[s])
    return steps, stages


def _time_loop(rig: StereoRig, backgrounds: list[StereoFrame], frames: list[StereoFrame], size: tuple[int, int]
               ) -> tuple[list[float], list[float]]:
    """Capture-to-command latency (ms) and the pipeline part of it, through the servo loop (IMM predictor,
    aim controller, simulated gimbal whose own modelled latency is not counted)."""
    from tracker.closedloop_eval import closed_loop_imm
    from tracker.servo.sim import SimulatedGimbal

    pipe = _pipeline(rig, backgrounds)
    loop = ServoLoop(pipe, AimController(AimConfig(frame_width_px=size[0], focal_px=pipe.rect.f)),
                     closed_loop_imm(), SimulatedGimbal(), LoopConfig())
    latency: list[float] = []
    pipeline: list[float] = []
    for f in frames:
        st = loop.step(f)
        latency.append(st.latency_ms)
        pipeline.append(st.pipeline_ms)
    return latency, pipeline


def _time_mog2(background: StereoFrame, frames: list[StereoFrame]) -> list[float]:
    """OpenCV MOG2 on both images of each frame (ms), after a few empty-scene frames."""
    mogs = (cv2.createBackgroundSubtractorMOG2(), cv2.createBackgroundSubtractorMOG2())
    for _ in range(5):
        mogs[0].apply(background.left)
        mogs[1].apply(background.right)
    out: list[float] = []
    for f in frames:
        t0 = time.perf_counter()
        mogs[0].apply(f.left)
        mogs[1].apply(f.right)
        out.append((time.perf_counter() - t0) * 1e3)
    return out
