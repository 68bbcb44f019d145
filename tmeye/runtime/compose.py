"""Composition of one rig: source, rig, background survey, pipeline, predictor, aim controller and servo
driver, from a `RuntimeConfig`. Used by the runtime (and so by `tmeye track` and `tmeye serve` alike).

Problems a user can fix (unknown scenario, missing rig file, a source or servo that will not open) raise
`ComposeError` with a one-line message.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from tmeye.runtime.config import RuntimeConfig, TrackerTuning
from tracker.aim import AimConfig, AimController
from tracker.closedloop import LoopConfig, ServoLoop, ServoSimSource, background_range, survey_grid, widen_background
from tracker.closedloop_eval import closed_loop_imm, mount_range
from tracker.evaluation import survey_poses, target_prior
from tracker.frames import FrameSource
from tracker.geometry import StereoRig, load_rig
from tracker.pipeline import Pipeline
from tracker.rigcheck import RigError
from tracker.servo import ServoError, SimulatedGimbal, open_servo
from tracker.servo.base import AxisLimits, ServoDriver
from tracker.sim.scenarios import SimRig, get_scenario
from tracker.solid_prior import SolidPrior


class ComposeError(ValueError):
    """The configuration cannot be composed into a running rig; the message is one line."""


@dataclass
class Composition:
    """The parts of one running rig. `source` yields frames; `loop` is None when no servo is driven;
    `sim` is the simulated rig when the source is simulated (for ground truth and skipping)."""

    config: RuntimeConfig
    rig: StereoRig
    source: FrameSource
    pipeline: Pipeline
    loop: ServoLoop | None
    controller: AimController | None
    driver: ServoDriver | None
    sim: SimRig | None
    fps: float
    track_limits: tuple[AxisLimits, AxisLimits] | None = None  # (pan, tilt) for automatic tracking

    def close(self) -> None:
        try:
            self.source.close()
        finally:
            if self.driver is not None:
                self.driver.close()


def compose(cfg: RuntimeConfig, tuning: TrackerTuning | None = None, rig: StereoRig | None = None) -> Composition:
    """Open the source and the servo, learn the background and build the loop. `rig` overrides the
    config's rig file (an activated calibration record)."""
    tuning = tuning or TrackerTuning()
    if rig is None and cfg.rig:
        try:
            rig = load_rig(cfg.rig, cfg.baseline_limits_m)
        except (OSError, ValueError, KeyError) as exc:
            raise ComposeError(str(exc)) from None
    if cfg.source == "sim":
        return _compose_sim(cfg, tuning, rig)
    if cfg.source == "recording":
        from tmeye.runtime.replay_compose import compose_recording

        return compose_recording(cfg, tuning, rig)
    return _compose_real(cfg, tuning, rig)


def pipeline(rig: StereoRig, cfg: RuntimeConfig, tuning: TrackerTuning, fps: float) -> Pipeline:
    with rig_errors(cfg):
        return Pipeline(rig, replace(tuning.detector, fps=fps), tuning.track_config(),
                        origin=np.array(cfg.origin, float),
                        verify_budget_ms=cfg.verify_budget_ms if cfg.realtime else None,
                        sigma_budget_ms=cfg.sigma_budget_ms if cfg.realtime else None, solid=solid_prior(cfg),
                        between_frames=cfg.realtime)  # the worker's time between frames (Runtime._between_frames)


def solid_prior(cfg: RuntimeConfig) -> SolidPrior | None:
    """The localiser's prior for cfg.targets (RuntimeConfig): with "auto", a simulated scene's own (solid
    bodies for NAME:body, none for plates), solid for real cameras and their recordings."""
    if cfg.targets != "auto":
        return SolidPrior() if cfg.targets == "solid" else None
    if cfg.source == "sim" or (cfg.source == "recording" and cfg.scenario):
        try:
            return target_prior(get_scenario(cfg.scenario))
        except ValueError as exc:
            raise ComposeError(str(exc)) from None
    return SolidPrior()


@contextmanager
def rig_errors(cfg: RuntimeConfig) -> Iterator[None]:
    """A RigError (the rig against the settings or the first frames) as a ComposeError naming the file."""
    try:
        yield
    except RigError as exc:
        raise ComposeError(f"rig file {cfg.rig}: {exc}" if cfg.rig else f"rig: {exc}") from None


def _compose_sim(cfg: RuntimeConfig, tuning: TrackerTuning, rig: StereoRig | None) -> Composition:
    try:
        scenario = get_scenario(cfg.scenario)
    except ValueError as exc:
        raise ComposeError(str(exc)) from None
    sim = SimRig(scenario, seed=cfg.seed)  # a finite scenario that should repeat is rewound by the runtime
    rig = rig or sim.rig
    pipe = pipeline(rig, cfg, tuning, scenario.fps)
    driver = _open_driver(cfg)
    source: FrameSource = sim
    loop = controller = None
    track_limits = None
    try:
        if driver is not None:
            pan, tilt = mount_range(scenario)
            widen_background(pipe, *background_range(pan, tilt, rig.left.size, pipe.rect.f))
            poses = survey_grid(pan, tilt)
            controller = _controller(pipe, tuning)
            track_limits = tracking_limits(controller.config, (pan, tilt))
            source = ServoSimSource(sim, driver, lambda: controller.setpoint)
            loop = _loop(pipe, controller, driver)
        else:
            poses = survey_poses(scenario)
        with rig_errors(cfg):
            for g in poses:
                pipe.learn_background(sim.background(g))
    except BaseException:
        if driver is not None:
            driver.close()
        raise
    return Composition(cfg, rig, source, pipe, loop, controller, driver, sim, scenario.fps, track_limits)


def _compose_real(cfg: RuntimeConfig, tuning: TrackerTuning, rig: StereoRig | None) -> Composition:
    from tracker.sources import SourceError, open_source

    if rig is None:
        raise ComposeError(f"source {cfg.source} needs a rig file (make one with `tmeye calibrate`)")
    driver = _open_driver(cfg)
    try:
        if isinstance(driver, SimulatedGimbal):
            raise ComposeError("servo sim drives the simulated rig: use it with the simulated source")
        try:
            src = open_source(cfg.source, list(cfg.inputs))
        except SourceError as exc:
            raise ComposeError(str(exc)) from None
        first = src.read()
        if first is None:
            src.close()
            raise ComposeError(f"{cfg.source} source gave no frames")
    except BaseException:
        if driver is not None:
            driver.close()
        raise
    fps = float(getattr(src, "fps", 0.0) or 30.0)
    try:
        pipe = pipeline(rig, cfg, tuning, fps)
        with rig_errors(cfg):
            pipe.learn_background_from_stream(first)  # the first pair, then the stream's robust statistics
    except BaseException:
        src.close()
        if driver is not None:
            driver.close()
        raise
    controller = _controller(pipe, tuning) if driver is not None else None
    loop = _loop(pipe, controller, driver) if controller is not None and driver is not None else None
    return Composition(cfg, rig, src, pipe, loop, controller, driver, None, fps)


def _open_driver(cfg: RuntimeConfig) -> ServoDriver | None:
    if not cfg.servo or cfg.servo == "none":
        return None
    try:
        return open_servo(cfg.servo)
    except ServoError as exc:
        raise ComposeError(str(exc)) from None


def _controller(pipe: Pipeline, tuning: TrackerTuning) -> AimController:
    return AimController(replace(tuning.aim, frame_width_px=pipe.rig.left.size[0], focal_px=pipe.rect.f))


def tracking_limits(aim: AimConfig, mount: tuple[tuple[float, float], tuple[float, float]]
                    ) -> tuple[AxisLimits, AxisLimits]:
    """The mechanical limits narrowed to the (pan, tilt) ranges in degrees whose background was surveyed:
    automatic tracking stays there (beyond it every pixel would look new); the operator may go anywhere."""
    (p0, p1), (t0, t1) = mount
    return (AxisLimits(max(p0, aim.pan_limits.min_deg), min(p1, aim.pan_limits.max_deg)),
            AxisLimits(max(t0, aim.tilt_limits.min_deg), min(t1, aim.tilt_limits.max_deg)))


def _loop(pipe: Pipeline, controller: AimController, driver: ServoDriver) -> ServoLoop:
    lead = 0.09
    latency: float | None = None
    if isinstance(driver, SimulatedGimbal):
        lead = driver.config.latency_s + driver.config.time_constant_s
        latency = 0.005  # simulated time: the loop's budget
    return ServoLoop(pipe, controller, closed_loop_imm(), driver, LoopConfig(lead_s=lead, latency_s=latency))


def rebuild_pipeline(comp: Composition, rig: StereoRig, tuning: TrackerTuning) -> Composition:
    """A new pipeline (and servo loop, sharing the running controller and driver) for `rig` on the same
    source. For the simulator the background is learnt from a second renderer of the same scene (the
    running one belongs to the worker); a real source's is learnt by the worker from its next frame and the
    stream after it."""
    pipe = pipeline(rig, comp.config, tuning, comp.fps)
    if comp.sim is not None:
        scenario = comp.sim.scenario
        twin = SimRig(scenario, seed=comp.config.seed)
        if comp.loop is not None:
            pan, tilt = mount_range(scenario)
            widen_background(pipe, *background_range(pan, tilt, rig.left.size, pipe.rect.f))
            poses = survey_grid(pan, tilt)
        else:
            poses = survey_poses(scenario)
        for g in poses:
            pipe.learn_background(twin.background(g))
    loop = None
    if comp.loop is not None and comp.controller is not None and comp.driver is not None:
        loop = _loop(pipe, comp.controller, comp.driver)
    return replace(comp, rig=rig, pipeline=pipe, loop=loop)


def describe_source(c: Composition) -> dict[str, Any]:
    """The source part of the status: kind, scenario or inputs, frame rate, image size, and the left camera's
    field of view (degrees, from the rig in use)."""
    w, h = c.rig.left.size
    hfov, vfov = c.rig.left.field_of_view_deg()
    out: dict[str, Any] = {"kind": c.config.source, "fps": c.fps, "width": w, "height": h,
                           "hfov_deg": round(hfov, 3), "vfov_deg": round(vfov, 3)}
    if c.config.source == "recording":
        out.update({"inputs": list(c.config.inputs), "start": c.config.start, "end": c.config.end})
    elif c.config.source == "sim":
        out.update({"scenario": c.config.scenario, "seed": c.config.seed})
    else:
        out["inputs"] = list(c.config.inputs)
    return out


def apply_tuning(comp: Composition, tuning: TrackerTuning) -> None:
    """New tracker settings, in the worker between frames: the detector, the tracks' and the aim's."""
    pipe = comp.pipeline
    det = replace(tuning.detector, fps=pipe.subtractor.cfg.fps, stride=pipe.subtractor.cfg.stride)
    pipe.subtractor.reconfigure(det)
    pipe.tracker.cfg = tuning.track_config()
    if comp.controller is not None:
        old = comp.controller.config
        comp.controller.config = replace(tuning.aim, frame_width_px=old.frame_width_px, focal_px=old.focal_px,
                                         pan_limits=old.pan_limits, tilt_limits=old.tilt_limits)
