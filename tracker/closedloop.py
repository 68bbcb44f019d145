"""Closing the loop: pipeline -> predictor -> aim controller -> servo driver, once per frame (`ServoLoop`).

Per frame: the pipeline localises the primary target (using the gimbal angles the frame carries); its
r, θ, φ update the predictor (`tracker.predict`) at capture time t; the predictor is asked for the target
at t + latency + lead, where latency is the capture-to-command time (measured, or a fixed model in
simulation) and lead is the mount's own delay (servo latency plus its time constant); the aim controller
(`tracker.aim`) turns that and the image-centroid offset into a command, sent to the driver.

Fault policy: a driver that reports a fault (`ServoDriver.fault`) is not stopped on: commands are still
attempted, but at most once per `retry_interval_s` (a silent serial device blocks for its timeout), and
the fault is reported in every `LoopStep`. The tracker keeps running without driving.

Also here: `ServoSimSource`, the simulated rig rendered from a SimulatedGimbal's angles (the loop closes
through the simulator), and `widen_background`, which makes a pipeline's background panorama cover a
wider pan/tilt range than its default.
"""

from __future__ import annotations

import math
import statistics
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Protocol

import numpy as np

from tracker.aim import AimInput, ServoCommand
from tracker.bgdepth import BackgroundDepth
from tracker.frames import GimbalState, StereoFrame
from tracker.pipeline import Pipeline
from tracker.predict import Measurement, PredictedState, TrackEstimate, UKFBankPredictor
from tracker.results import Detection, FrameResult
from tracker.servo.base import ServoDriver
from tracker.servo.sim import SimulatedGimbal
from tracker.sim.scenarios import SimRig

DEFAULT_LATENCY_S = 0.005  # the capture-to-command budget; the latency model before any is measured


class Aimer(Protocol):
    """What the loop needs of an aim controller (tracker.aim.AimController / ReactiveController)."""

    @property
    def setpoint(self) -> GimbalState: ...

    def step(self, inp: AimInput) -> ServoCommand | None: ...


@dataclass(frozen=True)
class LoopConfig:
    """Timing and measurement settings of the loop.

    lead_s: how far beyond the capture-to-command latency to predict (s): the mount's command latency
    plus its time constant (a first-order lag trails a ramp by τ). latency_s: the capture-to-command
    latency model (s); None: the running median of the last `latency_window` measured ones (wall clock).
    centroid_sigma_px / disparity_sigma_px: floors of the 1-σ used for the predictor's measurement (the
    pipeline's own σ assume a perfect calibration). retry_interval_s: while the driver reports a fault,
    commands are attempted at most this often (s). keepalive_s: a real (serial) driver that was sent nothing
    for this long is asked for its position, so a port that vanished while the mount stood still is
    reported as a fault within about this time (s)."""

    lead_s: float = 0.09
    latency_s: float | None = None
    latency_window: int = 50
    centroid_sigma_px: float = 0.3
    disparity_sigma_px: float = 0.05
    retry_interval_s: float = 1.0
    keepalive_s: float = 0.5


@dataclass(frozen=True)
class LoopStep:
    """What one frame did. horizon_s: prediction horizon beyond capture time (s). latency_ms: capture to
    command issued (pipeline + predictor + aim + driver call), wall clock; pipeline_ms: the pipeline step
    alone. command: None when nothing was sent (deadband, at goal, no target, or held back by a fault)."""

    frame: StereoFrame
    result: FrameResult
    measurement: Measurement | None
    estimate: TrackEstimate | None
    predicted: PredictedState | None
    horizon_s: float
    command: ServoCommand | None
    fault: str | None
    latency_ms: float
    pipeline_ms: float

    def servo_json(self) -> dict[str, object]:
        """The "servo" telemetry fields: mount angles of the frame (deg), the command sent (or None) and
        the driver's fault (or None)."""
        g = self.frame.gimbal or GimbalState()
        cmd = None if self.command is None else {"pan_deg": round(self.command.pan_deg, 4),
                                                 "tilt_deg": round(self.command.tilt_deg, 4),
                                                 "reason": self.command.reason}
        return {"pan_deg": round(g.pan_deg, 4), "tilt_deg": round(g.tilt_deg, 4), "command": cmd,
                "fault": self.fault}


def measurement_of(det: Detection, focal_px: float, baseline_m: float, cfg: LoopConfig) -> Measurement:
    """The predictor's spherical measurement of a detection, with 1-σ floored by the stereo model
    σ_r = r² σ_d / (f b), σ_θ = σ_φ = σ_px / f (and then the angles' σ scaled for cos φ on azimuth)."""
    loc = det.loc
    sr = loc.r * loc.r * cfg.disparity_sigma_px / (focal_px * baseline_m)
    sa = cfg.centroid_sigma_px / focal_px
    return Measurement(loc.r, loc.theta, loc.phi, max(loc.sigma_r, sr),
                       max(loc.sigma_theta, sa / max(math.cos(loc.phi), 0.1)), max(loc.sigma_phi, sa))


def centroid_offset(det: Detection, focal_px: float) -> tuple[float, float]:
    """The target's offset (du, dv) in pixels from the optical axis as seen from the rig origin (midway
    between the cameras): the mean of the left and right views, which cancels the ±b/2 parallax."""
    X = det.loc.rig
    return focal_px * float(X[0] / X[2]), focal_px * float(X[1] / X[2])


class ServoLoop:
    """One frame in, one command (or none) out. `predictor` None: the controller gets no prediction (the
    reactive baseline). `driver` None: compute commands without sending them."""

    def __init__(self, pipe: Pipeline, controller: Aimer, predictor: UKFBankPredictor | None,
                 driver: ServoDriver | None, config: LoopConfig | None = None):
        self.pipe = pipe
        self.controller = controller
        self.predictor = predictor
        self.driver = driver
        self.config = config or LoopConfig()
        self.focal_px = pipe.rect.f
        self._latencies: deque[float] = deque(maxlen=self.config.latency_window)
        self._last_attempt = -math.inf
        self._following: int | None = None  # the primary target's track id the predictor follows

    def latency_s(self) -> float:
        """The capture-to-command latency model (s): configured, or the median of recent measurements."""
        if self.config.latency_s is not None:
            return self.config.latency_s
        return statistics.median(self._latencies) if self._latencies else DEFAULT_LATENCY_S

    def prepare(self, frame: StereoFrame) -> StereoFrame:
        """A frame from a source that does not know the mount's angles gets the last commanded ones."""
        return frame if frame.gimbal is not None else replace(frame, gimbal=self.controller.setpoint)

    def step(self, frame: StereoFrame) -> LoopStep:
        """Process a captured frame and issue the command. For a SimulatedGimbal the command is given at
        capture time + the latency model (simulated time), so the loop's delay is part of the simulation."""
        t_have = time.perf_counter()
        frame = self.prepare(frame)
        res = self.pipe.step(frame)
        t_pipe = time.perf_counter()
        det = res.primary
        if res.primary_id is not None and res.primary_id != self._following:
            self._following = res.primary_id  # a new target (the tracker's or an operator's choice): the old
            if self.predictor is not None:  # one's motion says nothing of it
                self.predictor.reset()
        rect = self.pipe.rect
        z = None if det is None else measurement_of(det, rect.f, rect.b, self.config)
        est = pred = None
        horizon = self.latency_s() + self.config.lead_s
        if self.predictor is not None:
            est = self.predictor.update(frame.t, z)
            if est.state is not None:
                pred = self.predictor.predict_at(frame.t + horizon)
        centroid = None if det is None else centroid_offset(det, self.focal_px)
        cmd = self.controller.step(AimInput(frame.t, frame.gimbal, pred, None if est is None else est.state,
                                            centroid, 0.0 if est is None else est.coasting_s))
        cmd = self._send(frame, cmd)
        if cmd is None:
            self._keepalive()
        t_cmd = time.perf_counter()
        self._latencies.append(t_cmd - t_have)
        fault = None if self.driver is None else self.driver.fault
        return LoopStep(frame, res, z, est, pred, horizon, cmd, fault, (t_cmd - t_have) * 1e3,
                        (t_pipe - t_have) * 1e3)

    def _send(self, frame: StereoFrame, cmd: ServoCommand | None) -> ServoCommand | None:
        drv = self.driver
        if cmd is None or drv is None:
            return cmd
        if isinstance(drv, SimulatedGimbal):
            drv.advance(max(frame.t + self.latency_s(), drv.now))
        elif drv.fault is not None and time.monotonic() - self._last_attempt < self.config.retry_interval_s:
            return None  # faulted: do not block on a silent device every frame
        drv.command(cmd.pan_deg, cmd.tilt_deg)
        self._last_attempt = time.monotonic()
        return cmd

    def _keepalive(self) -> None:
        """Ask a real driver for its position when nothing was sent for keepalive_s (a fault shows up)."""
        drv = self.driver
        if drv is None or isinstance(drv, SimulatedGimbal):
            return
        now = time.monotonic()
        wait = self.config.retry_interval_s if drv.fault is not None else self.config.keepalive_s
        if now - self._last_attempt >= wait:
            self._last_attempt = now
            drv.read_position()


class ServoSimSource:
    """FrameSource: the simulated rig rendered from the mount's angles at each frame's time. With a
    SimulatedGimbal they are `state_at(t)`; with any other driver (hardware in the loop) they are
    `angles()` (e.g. the aim controller's last setpoint)."""

    def __init__(self, sim: SimRig, driver: ServoDriver, angles: Callable[[], GimbalState] | None = None):
        self.sim = sim
        self.scenario = sim.scenario
        self.driver = driver
        self.angles = angles

    def read(self) -> StereoFrame | None:
        if self.sim.exhausted:
            return None
        t = self.sim.index / self.sim.scenario.fps
        if isinstance(self.driver, SimulatedGimbal):
            g = self.driver.state_at(t)
        else:
            g = self.angles() if self.angles is not None else GimbalState()
        return self.sim.step(g).frame

    def close(self) -> None:
        self.driver.close()


def background_range(pan_deg: tuple[float, float], tilt_deg: tuple[float, float],
                     size: tuple[int, int], focal_px: float) -> tuple[float, float]:
    """The `BackgroundDepth` (pan_range_deg, tilt_range_deg) whose canvas holds every pixel of images
    (W, H) of focal f seen at gimbal angles in the given ranges (deg): the canvas half-width is
    W/2 + f tan(pan_range), and it must reach f tan(|pan| + half the field of view)."""
    w, h = size
    out = []
    for lim, half in ((pan_deg, w / 2.0), (tilt_deg, h / 2.0)):
        reach = max(abs(lim[0]), abs(lim[1])) + math.degrees(math.atan(half / focal_px))
        pad = focal_px * math.tan(math.radians(min(reach, 80.0))) - half
        out.append(math.degrees(math.atan(max(pad, 0.0) / focal_px)))
    return out[0], out[1]


def widen_background(pipe: Pipeline, pan_range_deg: float, tilt_range_deg: float) -> None:
    """Give the pipeline a background panorama covering ±pan_range_deg / ±tilt_range_deg (see
    BackgroundDepth); call before learning. Work-around: Pipeline has no parameter for the canvas range,
    so the BackgroundDepth object it shares with its subtractor is re-initialised in place."""
    wide = BackgroundDepth(pipe.rect, pan_range_deg, tilt_range_deg, near_m=pipe.bg.near_m)
    vars(pipe.bg).update(vars(wide))
    pipe.subtractor.reset_maps()


def survey_grid(pan_deg: tuple[float, float], tilt_deg: tuple[float, float], pan_step_deg: float = 20.0,
                tilt_step_deg: float = 24.0) -> list[GimbalState]:
    """Poses (deg) at which to learn the background before a run whose mount stays in the given ranges:
    from end to end, n + 1 of them where n = ceil(span / step) - 1 (so less than step + span / n apart:
    the 56° x 44° field of view still overlaps by more than half); a range narrower than its step gets one
    pose at its middle."""
    def axis(lo: float, hi: float, step: float) -> list[float]:
        n = int(math.ceil((hi - lo) / step)) - 1
        return [float(v) for v in np.linspace(lo, hi, n + 1)] if n > 0 else [0.5 * (lo + hi)]

    return [GimbalState(p, t) for t in axis(*tilt_deg, tilt_step_deg) for p in axis(*pan_deg, pan_step_deg)]
