"""Aiming the pan/tilt mount: `AimController` (prediction + image-centroid correction) and the comparison
baseline `ReactiveController` (proportional on the image-centroid error only).

Both turn per-frame inputs (`AimInput`) into absolute `ServoCommand`s in degrees (gimbal convention of
tracker.geometry: pan + turns +z toward +x, tilt + looks up; aiming at p means pan = deg θ, tilt = deg φ).
Shared behaviour (`AimConfig`):
- the commanded setpoint moves under a rate limit (deg/s) and an acceleration limit (deg/s²) per axis;
- mechanical limits are always clamped;
- deadband: while the setpoint is at rest and the aim error (goal minus setpoint, pan scaled by
  cos tilt) is below `deadband_frac` of the frame width (as an angle: atan(frac W / f)), no command is
  issued; once it moves it goes on until the goal is reached (hysteresis), sparing the motors;
- `loss_timeout_s` after the target was last measured the mount returns home (until then it follows the
  prediction while there is one, then holds);
- manual mode: `set_manual(pan, tilt)` overrides everything (still rate-limited) until `resume_auto()`.
`step()` returns None when there is nothing new to send.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import StrEnum

import numpy as np

from tracker.frames import GimbalState
from tracker.geometry import Camera, gimbal_rotation
from tracker.predict import F64, PredictedState
from tracker.servo.base import DEFAULT_PAN_LIMITS, DEFAULT_TILT_LIMITS, AxisLimits


@dataclass(frozen=True)
class AimConfig:
    """Controller settings. Pixels and focal length of the image the centroids come from; rates in deg/s,
    accelerations in deg/s², angles in degrees, times in seconds."""

    frame_width_px: int = 640
    focal_px: float = 600.0
    max_rate_deg_s: float = 180.0
    max_accel_deg_s2: float = 1200.0
    pan_limits: AxisLimits = field(default_factory=lambda: DEFAULT_PAN_LIMITS)
    tilt_limits: AxisLimits = field(default_factory=lambda: DEFAULT_TILT_LIMITS)
    deadband_frac: float = 0.02
    loss_timeout_s: float = 1.5
    home_pan_deg: float = 0.0
    home_tilt_deg: float = 0.0
    centroid_gain: float = 1.0  # AimController: weight of the image-centroid correction (0 = off)
    correction_tau_s: float = 0.5  # AimController: low-pass time constant of that correction
    max_correction_deg: float = 5.0  # AimController: bound on the correction per axis
    reactive_gain: float = 0.5  # ReactiveController: fraction of the centroid error corrected per frame

    @property
    def deadband_deg(self) -> float:
        """The deadband as an angle: atan(deadband_frac · W / f) in degrees."""
        return math.degrees(math.atan(self.deadband_frac * self.frame_width_px / self.focal_px))


@dataclass(frozen=True)
class ServoCommand:
    """Absolute angles (degrees) to send at time t (s). reason: 'track' (prediction), 'centroid' (image
    only, no 3-D yet), 'reactive' (ReactiveController), 'home' (target lost), 'manual' (operator)."""

    pan_deg: float
    tilt_deg: float
    t: float
    reason: str


@dataclass(frozen=True)
class AimInput:
    """One frame's worth of information (all optional but t).

    t: now (s). gimbal: the mount's angles when the frame was captured (None: the last setpoint is used).
    predicted: the predictor's state at the time the command will take effect (t + servo latency), from
    `Predictor.predict_at`. current: its estimate at capture time (used with the centroid to measure
    the pointing bias). centroid_px: the target centroid's offset (du, dv) in pixels from the principal
    point, u right, v down, averaged over the left and right images (the mean cancels the ±b/2 parallax).
    coasting_s: how long (s) the predicted target has gone unmeasured (`Predictor.coasting_s`): the loss
    timeout counts from its last measurement, not from when the prediction runs out.
    """

    t: float
    gimbal: GimbalState | None = None
    predicted: PredictedState | None = None
    current: PredictedState | None = None
    centroid_px: tuple[float, float] | None = None
    coasting_s: float = 0.0


class AimMode(StrEnum):
    AUTO = "auto"
    MANUAL = "manual"


def aim_angles(p: F64) -> tuple[float, float]:
    """(pan, tilt) in degrees that point the optical axis at world point/direction p: (deg θ, deg φ)."""
    x, y, z = float(p[0]), float(p[1]), float(p[2])
    return math.degrees(math.atan2(x, z)), math.degrees(math.atan2(-y, math.hypot(x, z)))


def centroid_direction(g: GimbalState, du: float, dv: float, focal_px: float) -> tuple[float, float]:
    """Absolute (pan, tilt) in degrees of the ray through pixel offset (du, dv) seen at gimbal angles g:
    d_world = R_world_rig(g) @ [du/f, dv/f, 1] (exact, no small-angle approximation)."""
    d = gimbal_rotation(g.pan_deg, g.tilt_deg) @ np.array([du / focal_px, dv / focal_px, 1.0])
    return aim_angles(d)


def point_angles(cam: Camera, u: float, v: float, distance_m: float, g: GimbalState,
                 iterations: int = 6) -> tuple[float, float]:
    """(pan, tilt) in degrees that bring the scene point seen at raw pixel (u, v) of camera `cam` (at
    gimbal angles g, `distance_m` along its ray) onto that camera's optical axis.

    The point is X = R_world_rig(g) (c + t d) for the pixel's rig-frame ray d and lens centre c; the axis
    of the camera at new angles g' passes through R(g') (c + s e_z). The camera sits off the pivot, so
    the angles are found by fixed-point iteration: aim the pivot's axis at X - R(g') c (exact in the
    limit; the offset |c| is small against the distance, so it converges in a few steps)."""
    d = cam.rays_rig(np.array([u], float), np.array([v], float))[0]
    X = gimbal_rotation(g.pan_deg, g.tilt_deg) @ (cam.c + distance_m * d)
    axis_c = cam.R_rc.T @ np.array([0.0, 0.0, 1.0])  # the camera's axis in the rig frame
    pan, tilt = aim_angles(X)
    for _ in range(iterations):
        R = gimbal_rotation(pan, tilt)
        # the pivot's axis aimed at X - R c, corrected for the camera's axis direction in the rig frame
        want = X - R @ cam.c
        pan, tilt = aim_angles(want)
        if abs(axis_c[0]) + abs(axis_c[1]) > 1e-9:
            dp, dt = aim_angles(axis_c)
            pan, tilt = pan - dp, tilt - dt
    return pan, tilt


def _wrap_deg(a: float) -> float:
    return (a + 180.0) % 360.0 - 180.0


def _slew(pos: float, vel: float, goal: float, dt: float, vmax: float, amax: float) -> tuple[float, float]:
    """One step of a rate- and acceleration-limited approach to goal; returns (pos, vel)."""
    e = goal - pos
    v_stop = math.sqrt(2.0 * amax * abs(e))  # fastest speed from which we can still stop at the goal
    v_want = math.copysign(min(vmax, v_stop, abs(e) / dt), e)
    vel += min(max(v_want - vel, -amax * dt), amax * dt)  # |dv| <= a dt
    new = pos + vel * dt
    if (goal - new) * e <= 0.0 and abs(vel) <= 2.0 * amax * dt:  # arrived: stop there
        return goal, 0.0
    return new, vel


class _AimBase:
    """Setpoint dynamics, limits, deadband, loss timeout, home and manual mode; subclasses choose the goal."""

    def __init__(self, config: AimConfig | None = None):
        self.config = cfg = config or AimConfig()
        self._pan, self._tilt = cfg.home_pan_deg, cfg.home_tilt_deg
        self._vpan = self._vtilt = 0.0
        self._goal: tuple[float, float] = (self._pan, self._tilt)
        self._goal_reason = "home"
        self._moving = False
        self._t: float | None = None
        self._last_seen: float | None = None
        self._manual: tuple[float, float] | None = None

    @property
    def setpoint(self) -> GimbalState:
        """The last commanded (or initial, home) angles in degrees."""
        return GimbalState(self._pan, self._tilt)

    @property
    def mode(self) -> AimMode:
        return AimMode.MANUAL if self._manual is not None else AimMode.AUTO

    def set_manual(self, pan_deg: float, tilt_deg: float) -> None:
        """Operator override: go to these angles (clamped) and ignore targets until resume_auto()."""
        self._manual = (self.config.pan_limits.clamp(pan_deg), self.config.tilt_limits.clamp(tilt_deg))

    def resume_auto(self) -> None:
        """Leave manual mode; the loss timeout restarts now."""
        self._manual = None
        self._last_seen = self._t

    def step(self, inp: AimInput) -> ServoCommand | None:
        """Advance to inp.t and return the command to send, or None (inside the deadband, at the goal,
        or holding while the target is briefly missing)."""
        dt = 0.0 if self._t is None else inp.t - self._t
        if dt < 0.0:
            raise ValueError(f"aim time went backwards ({inp.t:.6f} < {self._t:.6f} s)")
        self._t = inp.t
        if self._last_seen is None:
            self._last_seen = inp.t
        goal, reason = self._choose_goal(inp, dt)
        if goal is not None:
            self._goal, self._goal_reason = goal, reason
        if not self._moving:
            if self._deadband_error() <= self._start_threshold():
                return None
            self._moving = True
        return self._move(dt)

    # --- internals ---------------------------------------------------------------------------------

    def _choose_goal(self, inp: AimInput, dt: float) -> tuple[tuple[float, float] | None, str]:
        cfg = self.config
        if self._manual is not None:
            return self._manual, "manual"
        goal, reason = self._auto_goal(inp, dt)
        assert self._last_seen is not None
        if goal is not None:  # a target: seen, or predicted since it was last measured
            self._last_seen = max(self._last_seen, inp.t - inp.coasting_s)
        if inp.t - self._last_seen > cfg.loss_timeout_s:
            return (cfg.home_pan_deg, cfg.home_tilt_deg), "home"
        if goal is None:
            return None, ""  # hold: keep the previous goal
        return (cfg.pan_limits.clamp(goal[0]), cfg.tilt_limits.clamp(goal[1])), reason

    def _auto_goal(self, inp: AimInput, dt: float) -> tuple[tuple[float, float] | None, str]:
        raise NotImplementedError

    def _aim_error(self) -> float:
        """Angular aim error in degrees: hypot(Δpan cos tilt, Δtilt)."""
        dpan = _wrap_deg(self._goal[0] - self._pan) * math.cos(math.radians(self._tilt))
        return math.hypot(dpan, self._goal[1] - self._tilt)

    def _deadband_error(self) -> float:
        """The error compared with the deadband before starting to move (degrees)."""
        return self._aim_error()

    def _start_threshold(self) -> float:
        """Tracking waits for the deadband; home and manual goals are always reached exactly."""
        return self.config.deadband_deg if self._goal_reason in ("track", "centroid", "reactive") else 1e-9

    def _move(self, dt: float) -> ServoCommand | None:
        cfg = self.config
        if dt <= 0.0:
            return None
        old = (self._pan, self._tilt)
        self._pan, self._vpan = _slew(
            self._pan, self._vpan, self._goal[0], dt, cfg.max_rate_deg_s, cfg.max_accel_deg_s2
        )
        self._tilt, self._vtilt = _slew(
            self._tilt, self._vtilt, self._goal[1], dt, cfg.max_rate_deg_s, cfg.max_accel_deg_s2
        )
        pan, tilt = cfg.pan_limits.clamp(self._pan), cfg.tilt_limits.clamp(self._tilt)
        if pan != self._pan:
            self._pan, self._vpan = pan, 0.0
        if tilt != self._tilt:
            self._tilt, self._vtilt = tilt, 0.0
        if self._vpan == 0.0 and self._vtilt == 0.0 and self._aim_error() < 1e-9:
            self._moving = False  # reached the goal: the deadband applies again
        if (self._pan, self._tilt) == old:
            return None
        assert self._t is not None
        return ServoCommand(self._pan, self._tilt, self._t, self._goal_reason)


class AimController(_AimBase):
    """Aims at the predicted 3-D position (absolute angles), corrected by a low-passed pointing bias
    measured from the image centroid: bias = direction(centroid) - direction(current estimate). Without
    a 3-D state but with a centroid it aims at the centroid's direction (reason 'centroid')."""

    def __init__(self, config: AimConfig | None = None):
        super().__init__(config)
        self._bias = (0.0, 0.0)

    @property
    def bias_deg(self) -> tuple[float, float]:
        """The current centroid correction (pan, tilt) in degrees."""
        return self._bias

    def _auto_goal(self, inp: AimInput, dt: float) -> tuple[tuple[float, float] | None, str]:
        cfg = self.config
        g = inp.gimbal or self.setpoint
        seen = None
        if inp.centroid_px is not None:
            seen = centroid_direction(g, inp.centroid_px[0], inp.centroid_px[1], cfg.focal_px)
        if inp.predicted is None:
            return (seen, "centroid") if seen is not None else (None, "")
        if seen is not None and inp.current is not None:
            now = aim_angles(inp.current.position)
            raw = (_wrap_deg(seen[0] - now[0]), seen[1] - now[1])
            k = 1.0 - math.exp(-dt / cfg.correction_tau_s) if dt > 0.0 else 0.0  # first-order low-pass
            lim = cfg.max_correction_deg
            self._bias = (
                min(max(self._bias[0] + k * (raw[0] - self._bias[0]), -lim), lim),
                min(max(self._bias[1] + k * (raw[1] - self._bias[1]), -lim), lim),
            )
        pan, tilt = aim_angles(inp.predicted.position)
        return (pan + cfg.centroid_gain * self._bias[0], tilt + cfg.centroid_gain * self._bias[1]), "track"


class ReactiveController(_AimBase):
    """Baseline: goal = g + K (direction(centroid) - g) with g the capture-time gimbal angles and
    K = reactive_gain; no prediction, no 3-D. The deadband applies to the full centroid error."""

    def __init__(self, config: AimConfig | None = None):
        super().__init__(config)
        self._seen_error = 0.0

    def _deadband_error(self) -> float:
        return self._seen_error if self._goal_reason == "reactive" else self._aim_error()

    def _auto_goal(self, inp: AimInput, dt: float) -> tuple[tuple[float, float] | None, str]:
        if inp.centroid_px is None:
            return None, ""
        g = inp.gimbal or self.setpoint
        pan, tilt = centroid_direction(g, inp.centroid_px[0], inp.centroid_px[1], self.config.focal_px)
        k = self.config.reactive_gain
        dpan = _wrap_deg(pan - g.pan_deg)
        self._seen_error = math.hypot(dpan * math.cos(math.radians(g.tilt_deg)), tilt - g.tilt_deg)
        return (g.pan_deg + k * dpan, g.tilt_deg + k * (tilt - g.tilt_deg)), "reactive"
