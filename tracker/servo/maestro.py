"""Pololu Maestro servo controller over its USB/TTL serial port, compact protocol.

Commands (bytes; 14-bit values are sent as low 7 bits then high 7 bits):
    set target        0x84, channel, target & 0x7F, (target >> 7) & 0x7F    target in quarter-µs
    set speed         0x87, channel, speed lo7, speed hi7                    0.25 µs / 10 ms (0 = no limit)
    set acceleration  0x89, channel, accel lo7, accel hi7                    0.25 µs / 10 ms / 80 ms
    get position      0x90, channel        -> 2 bytes little-endian, quarter-µs
    get errors        0xA1                 -> 2 bytes little-endian error bits (reading clears them)
The Maestro has no position feedback: "position" is the pulse width it is currently producing, i.e. the
target after its speed/acceleration limiting. Fault policy: see tracker.servo.base; `command()` also
reads the error register, so a Maestro that stops answering is noticed at the next command.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

from tracker.frames import GimbalState
from tracker.servo.base import ServoError
from tracker.servo.link import SerialLink

SET_TARGET, SET_SPEED, SET_ACCEL, GET_POSITION, GET_ERRORS = 0x84, 0x87, 0x89, 0x90, 0xA1
ERROR_BITS = (
    "serial signal",
    "serial overrun",
    "serial buffer full",
    "serial CRC",
    "serial protocol",
    "serial timeout",
    "script stack",
    "script call stack",
    "script program counter",
)


@dataclass(frozen=True)
class AxisCalibration:
    """Maps one axis' angle (degrees, gimbal convention) to a Maestro channel's pulse width (µs):
    µs = center_us + deg · us_per_deg (a negative us_per_deg reverses the servo). Angles are clamped to
    [min_deg, max_deg] and pulse widths to [min_us, max_us]."""

    channel: int
    center_us: float = 1500.0
    us_per_deg: float = 2000.0 / 180.0
    min_us: float = 500.0
    max_us: float = 2500.0
    min_deg: float = -90.0
    max_deg: float = 90.0

    def to_us(self, deg: float) -> float:
        """Pulse width in µs for an angle in degrees (both clamped)."""
        deg = min(max(deg, self.min_deg), self.max_deg)
        return min(max(self.center_us + deg * self.us_per_deg, self.min_us), self.max_us)

    def to_deg(self, us: float) -> float:
        """Angle in degrees for a pulse width in µs: (µs - center) / (µs per degree)."""
        return (us - self.center_us) / self.us_per_deg


def encode(command: int, channel: int, value: int) -> bytes:
    """A 4-byte compact-protocol command with a 14-bit value."""
    if not 0 <= value < 1 << 14:
        raise ValueError(f"Maestro value {value} does not fit in 14 bits")
    return bytes([command, channel, value & 0x7F, (value >> 7) & 0x7F])


def describe_errors(bits: int) -> str:
    """'serial protocol, serial timeout' for the set error bits."""
    names = [name for i, name in enumerate(ERROR_BITS) if bits >> i & 1]
    return ", ".join(names) or "none"


@dataclass(frozen=True)
class MaestroConfig:
    """Channels and calibrations; speed/acceleration limits in Maestro units (0 = unlimited), sent on
    every (re)connection."""

    pan: AxisCalibration = field(default_factory=lambda: AxisCalibration(0))
    tilt: AxisCalibration = field(default_factory=lambda: AxisCalibration(1, min_deg=-30.0, max_deg=80.0))
    speed: int = 0
    acceleration: int = 0


class MaestroDriver:
    """`ServoDriver` for a Pololu Maestro. Raises ServoError if the port cannot be opened or the Maestro
    does not answer a get-errors request at start-up."""

    def __init__(
        self,
        path: str,
        baud: int = 115200,
        timeout_s: float = 0.2,
        config: MaestroConfig | None = None,
        reconnect_interval_s: float = 1.0,
        clock: Callable[[], float] = time.monotonic,
    ):
        self.config = config or MaestroConfig()
        self.link = SerialLink(path, baud, timeout_s, "Maestro", reconnect_interval_s, clock)
        self.link.open()
        self.link.on_reopen = self._setup
        self.last_errors = 0
        if not self._setup():
            fault = self.link.fault
            self.link.close()
            raise ServoError(f"{fault} (is it a Maestro, in USB dual-port mode, at this baud rate?)")

    @property
    def fault(self) -> str | None:
        """None when healthy, else a one-line reason (see tracker.servo.base)."""
        return self.link.fault

    def command(self, pan_deg: float, tilt_deg: float) -> None:
        """Set both targets (clamped by the calibrations), then read the error register."""
        data = b"".join(
            encode(SET_TARGET, cal.channel, round(4.0 * cal.to_us(deg)))  # quarter-µs
            for cal, deg in ((self.config.pan, pan_deg), (self.config.tilt, tilt_deg))
        )
        if self.link.write(data):
            self.read_errors()

    def read_position(self) -> GimbalState | None:
        """Angles of the pulse widths being produced now, or None while faulted."""
        angles = []
        for cal in (self.config.pan, self.config.tilt):
            reply = self.link.request(bytes([GET_POSITION, cal.channel]), 2)
            if reply is None:
                return None
            angles.append(cal.to_deg(int.from_bytes(reply, "little") / 4.0))  # quarter-µs -> µs -> deg
        return GimbalState(angles[0], angles[1])

    def read_errors(self) -> int | None:
        """The error register (cleared by reading), or None while faulted. Non-zero bits set `fault`."""
        reply = self.link.request(bytes([GET_ERRORS]), 2)
        if reply is None:
            return None
        self.last_errors = bits = int.from_bytes(reply, "little")
        if bits:
            self.link.fault = f"Maestro reported errors 0x{bits:04X}: {describe_errors(bits)}"
        return bits

    def close(self) -> None:
        self.link.close()

    def _setup(self) -> bool:
        """Speed and acceleration limits on both channels, then a liveness check (get errors)."""
        cfg = self.config
        data = b"".join(
            encode(SET_SPEED, cal.channel, cfg.speed) + encode(SET_ACCEL, cal.channel, cfg.acceleration)
            for cal in (cfg.pan, cfg.tilt)
        )
        return self.link.write(data) and self.read_errors() is not None
