"""SimulatedGimbal: a deterministic pan/tilt mount driven by the caller's clock (the default driver).

Per axis: a command takes effect `latency_s` after it is given; the motor then follows the target as a
first-order lag (time constant τ) whose speed is limited to `max_rate_deg_s`; the load (the cameras)
follows the motor through a backlash (dead zone) of `backlash_deg`. Targets are clamped to the axis
limits. The simulated rig renders from `state_at(t)`, which closes the loop.

Time is the caller's (scenario seconds): `advance(t)` integrates exactly (closed form, no step size) up to
t, `command()` is stamped with the time of the last `advance`/`state_at` call.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field

from tracker.frames import GimbalState
from tracker.servo.base import DEFAULT_PAN_LIMITS, DEFAULT_TILT_LIMITS, AxisLimits


@dataclass(frozen=True)
class SimGimbalConfig:
    """time_constant_s: first-order lag τ (s); max_rate_deg_s: slew limit (deg/s); latency_s: command to
    motion delay (s); backlash_deg: total play between motor and load (deg); limits in degrees; start
    angles in degrees."""

    time_constant_s: float = 0.06
    max_rate_deg_s: float = 250.0
    latency_s: float = 0.03
    backlash_deg: float = 0.2
    pan_limits: AxisLimits = field(default_factory=lambda: DEFAULT_PAN_LIMITS)
    tilt_limits: AxisLimits = field(default_factory=lambda: DEFAULT_TILT_LIMITS)
    start_pan_deg: float = 0.0
    start_tilt_deg: float = 0.0


def slew_first_order(m: float, c: float, dt: float, tau: float, rate: float) -> float:
    """Motor angle after dt seconds of dm/dt = clamp((c - m)/τ, ±rate), starting at m, target c.

    While |c - m| > rate·τ the rate limit holds (linear slew); after that the lag is exponential:
    m(t) = c - (c - m0) e^(-t/τ)."""
    e = c - m
    if tau <= 0.0:  # no lag: pure rate limit
        step = rate * dt
        return c if abs(e) <= step else m + math.copysign(step, e)
    if abs(e) > rate * tau:
        t_sat = (abs(e) - rate * tau) / rate  # time spent slewing at the rate limit
        if dt <= t_sat:
            return m + math.copysign(rate * dt, e)
        m, dt = c - math.copysign(rate * tau, e), dt - t_sat
        e = c - m
    return c - e * math.exp(-dt / tau)  # m(t) = c - e0 e^(-t/τ)


def play(load: float, motor: float, backlash: float) -> float:
    """Load angle after the motor moved monotonically to `motor`: the load only moves when the motor
    pushes on one side of the dead zone |motor - load| <= backlash/2."""
    half = 0.5 * backlash
    if motor - load > half:
        return motor - half
    if load - motor > half:
        return motor + half
    return load


@dataclass
class _Axis:
    limits: AxisLimits
    target: float
    motor: float
    load: float

    def advance(self, dt: float, cfg: SimGimbalConfig) -> None:
        self.motor = slew_first_order(self.motor, self.target, dt, cfg.time_constant_s, cfg.max_rate_deg_s)
        self.load = play(self.load, self.motor, cfg.backlash_deg)  # motion within dt is monotonic


class SimulatedGimbal:
    """Deterministic simulated mount; implements `ServoDriver` plus `advance`/`state_at`/`now`."""

    def __init__(self, config: SimGimbalConfig | None = None, t0: float = 0.0):
        self.config = cfg = config or SimGimbalConfig()
        p0, t0_deg = cfg.pan_limits.clamp(cfg.start_pan_deg), cfg.tilt_limits.clamp(cfg.start_tilt_deg)
        self._pan = _Axis(cfg.pan_limits, p0, p0, p0)
        self._tilt = _Axis(cfg.tilt_limits, t0_deg, t0_deg, t0_deg)
        self._now = t0
        self._pending: deque[tuple[float, float, float]] = deque()  # (t_effective, pan, tilt)
        self.fault: str | None = None
        self.commands: list[tuple[float, float, float]] = []  # (t, pan, tilt) as given, for inspection

    @property
    def now(self) -> float:
        """The simulation time (s) reached by the last advance/state_at call."""
        return self._now

    @property
    def target(self) -> GimbalState:
        """The target the motors are currently driving to (commands in flight not included)."""
        return GimbalState(self._pan.target, self._tilt.target)

    def command(self, pan_deg: float, tilt_deg: float) -> None:
        """New target (degrees, clamped to limits), taking effect at now + latency_s."""
        pan, tilt = self._pan.limits.clamp(pan_deg), self._tilt.limits.clamp(tilt_deg)
        self.commands.append((self._now, pan, tilt))
        self._pending.append((self._now + self.config.latency_s, pan, tilt))

    def advance(self, t: float) -> None:
        """Integrate the dynamics up to time t (s); t must not go backwards."""
        if t < self._now:
            raise ValueError(f"simulated gimbal time cannot go backwards ({t:.6f} < {self._now:.6f} s)")
        while self._pending and self._pending[0][0] <= t:
            t_eff, pan, tilt = self._pending.popleft()
            self._step_to(max(t_eff, self._now))
            self._pan.target, self._tilt.target = pan, tilt
        self._step_to(t)

    def state_at(self, t: float) -> GimbalState:
        """The load (camera) angles at time t (s), after advancing to t."""
        self.advance(t)
        return GimbalState(self._pan.load, self._tilt.load)

    def read_position(self) -> GimbalState | None:
        """The load angles at `now` (a simulated mount never faults)."""
        return GimbalState(self._pan.load, self._tilt.load)

    def close(self) -> None:
        """Nothing to release."""

    def _step_to(self, t: float) -> None:
        dt = t - self._now
        if dt > 0.0:
            self._pan.advance(dt, self.config)
            self._tilt.advance(dt, self.config)
            self._now = t
