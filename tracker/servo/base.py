"""The servo-driver interface (a swap point) and what every driver shares.

Fault policy (all drivers): only opening raises `ServoError` (bad URL, missing or unopenable port, a
device that does not answer the hello). Once open, an I/O failure never raises: the driver sets
`fault` to a one-line reason, `command()` drops the command and `read_position()` returns None, and
the driver tries to reopen its port at a bounded rate (see `tracker.servo.link.SerialLink`). `fault`
returns to None as soon as the device answers again. So the tracker keeps running without driving.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from tracker.frames import GimbalState


class ServoError(RuntimeError):
    """A servo driver could not be opened; the message is one line."""


@dataclass(frozen=True)
class AxisLimits:
    """Mechanical range of one axis in degrees (gimbal convention: pan + right, tilt + up)."""

    min_deg: float
    max_deg: float

    def clamp(self, deg: float) -> float:
        """deg limited to [min_deg, max_deg]."""
        return min(max(deg, self.min_deg), self.max_deg)


DEFAULT_PAN_LIMITS = AxisLimits(-170.0, 170.0)
DEFAULT_TILT_LIMITS = AxisLimits(-30.0, 80.0)


class ServoDriver(Protocol):
    """A pan/tilt mount. Angles in degrees, absolute, in the convention of tracker.geometry.

    `command` sets new targets (clamped to the mount's limits; never raises once open).
    `read_position` returns the angles the device reports, or None while faulted. For hobby servos
    without feedback this is the position the controller is driving the servo to (Maestro: the
    speed/acceleration-limited target; ASCII boards: the last accepted command).
    `fault` is None when healthy, else a one-line reason. `close` releases the port (idempotent).
    """

    @property
    def fault(self) -> str | None: ...

    def command(self, pan_deg: float, tilt_deg: float) -> None: ...

    def read_position(self) -> GimbalState | None: ...

    def close(self) -> None: ...
