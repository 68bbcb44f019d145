"""Operator control of the mount: modes (auto, manual, hold, home), go-to, jog and their state.

`ServoControl` is owned by the worker thread: requests from other threads are queued by the runtime and
applied at the start of a frame (`apply`), and the per-frame jog motion is integrated there (`tick`).
Angles in degrees (gimbal convention of tracker.geometry: pan + right, tilt + up), rates in deg/s.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from enum import StrEnum

from tracker.aim import AimController
from tracker.servo.base import AxisLimits

MAX_JOG_S = 10.0


class ServoMode(StrEnum):
    AUTO = "auto"  # follow the primary target
    MANUAL = "manual"  # go to and stay at the operator's angles (goto, jog, presets)
    HOLD = "hold"  # stay where the mount is now
    HOME = "home"  # go to the home angles and stay there


class ServoRequestError(ValueError):
    """A control request that cannot be honoured (e.g. angles outside the mount's limits)."""


@dataclass(frozen=True)
class Jog:
    pan_dps: float
    tilt_dps: float
    until_t: float | None  # source time (s) the jog ends; None until the first frame after the request
    duration_s: float


def check_angles(pan_deg: float, tilt_deg: float, pan: AxisLimits, tilt: AxisLimits) -> None:
    """ServoRequestError unless both angles lie within the mount's limits."""
    for name, v, lim in (("pan_deg", pan_deg, pan), ("tilt_deg", tilt_deg, tilt)):
        if not lim.min_deg <= v <= lim.max_deg:
            raise ServoRequestError(f"{name} {v:g} is outside the mount's range "
                                    f"{lim.min_deg:g} to {lim.max_deg:g} degrees")


ServoWish = tuple[ServoMode, tuple[float, float] | None]  # a mode and its goal, what restore() goes back to


class ServoControl:
    """The operator's wishes applied to an AimController (whose manual mode does the rate-limited motion)."""

    def __init__(self, controller: AimController, track_limits: tuple[AxisLimits, AxisLimits] | None = None):
        """track_limits: (pan, tilt) limits in auto mode (the surveyed range); the operator's commands
        honour the mount's own limits, those the controller was built with."""
        self.controller = controller
        c = controller.config
        self.limits: tuple[AxisLimits, AxisLimits] = (c.pan_limits, c.tilt_limits)
        self.track_limits = track_limits or self.limits
        self.mode = ServoMode.AUTO
        self.goal: tuple[float, float] | None = None
        self._jog: Jog | None = None
        self._use(self.track_limits)

    def _use(self, limits: tuple[AxisLimits, AxisLimits]) -> None:
        self.controller.config = replace(self.controller.config, pan_limits=limits[0], tilt_limits=limits[1])

    def set_mode(self, mode: ServoMode) -> None:
        c = self.controller
        self._jog = None
        if mode is ServoMode.AUTO:
            self._use(self.track_limits)
            c.resume_auto()
            self.goal = None
        elif mode is ServoMode.HOME:
            self._manual((c.config.home_pan_deg, c.config.home_tilt_deg))
        elif mode in (ServoMode.HOLD, ServoMode.MANUAL):
            sp = c.setpoint
            self._manual((sp.pan_deg, sp.tilt_deg))
        self.mode = mode

    def wish(self) -> ServoWish:
        """The operator's mode and goal now (restore() goes back to them)."""
        return self.mode, self.goal

    def restore(self, wish: ServoWish) -> None:
        """Back to an earlier mode and goal (a request undone: its audit record could not be stored)."""
        mode, goal = wish
        if mode is ServoMode.AUTO or goal is None:
            self.set_mode(mode)
            return
        self._jog = None
        self._manual(goal)
        self.mode = mode

    def goto(self, pan_deg: float, tilt_deg: float) -> None:
        check_angles(pan_deg, tilt_deg, *self.limits)
        self._jog = None
        self._manual((pan_deg, tilt_deg))
        self.mode = ServoMode.MANUAL

    def jog(self, pan_dps: float, tilt_dps: float, duration_s: float) -> None:
        """Move at these rates for duration_s from now. A jog that arrives while another runs replaces its
        rates and end but goes on from the same goal, so a client that repeats short jogs (a held key, a
        gamepad polled every animation frame) moves the mount smoothly, however often it repeats them."""
        if self._jog is None or self.goal is None:
            sp = self.controller.setpoint  # start from where the mount is commanded now
            self._manual((sp.pan_deg, sp.tilt_deg))
        self._jog = Jog(pan_dps, tilt_dps, None, duration_s)
        self.mode = ServoMode.MANUAL

    def tick(self, t: float, dt: float) -> None:
        """Advance an active jog to source time t (s), dt seconds after the previous frame."""
        jog = self._jog
        if jog is None or self.goal is None:
            return
        until = jog.until_t
        if until is None:  # requested during the last frame interval: it runs from that interval's start
            until = t - dt + jog.duration_s
            self._jog = jog = Jog(jog.pan_dps, jog.tilt_dps, until, jog.duration_s)
        step = max(0.0, min(dt, until - (t - dt)))
        pan_l, tilt_l = self.limits
        self._manual((pan_l.clamp(self.goal[0] + jog.pan_dps * step), tilt_l.clamp(self.goal[1] + jog.tilt_dps * step)))
        if t >= until:
            self._jog = None

    def _manual(self, goal: tuple[float, float]) -> None:
        self._use(self.limits)
        self.goal = goal
        self.controller.set_manual(*goal)
