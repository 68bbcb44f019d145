"""Driver for boards speaking the TMEye servo ASCII protocol (docs/servo-ascii-protocol.md), e.g. the
Arduino sketch in firmware/arduino/tmeye_servo.

`P <pan> <tilt>` -> `OK`, `Q` -> `POS <pan> <tilt>`, `H` -> `TMEYE-SERVO 1 <limits>`, errors `ERR <text>`.
Fault policy: see tracker.servo.base (open raises ServoError; afterwards `fault` is set, nothing raises).
"""

from __future__ import annotations

import time
from collections.abc import Callable

from tracker.frames import GimbalState
from tracker.servo.base import DEFAULT_PAN_LIMITS, DEFAULT_TILT_LIMITS, AxisLimits, ServoError
from tracker.servo.link import SerialLink

PROTOCOL = "TMEYE-SERVO"
PROTOCOL_VERSION = 1


def parse_hello(reply: str) -> tuple[AxisLimits, AxisLimits]:
    """'TMEYE-SERVO 1 pmin pmax tmin tmax' -> (pan limits, tilt limits); ValueError if it is not one."""
    parts = reply.split()
    if len(parts) != 6 or parts[0] != PROTOCOL:
        raise ValueError(f"not a TMEye servo board (hello reply {reply!r})")
    if parts[1] != str(PROTOCOL_VERSION):
        raise ValueError(f"board speaks protocol version {parts[1]}, this TMEye speaks {PROTOCOL_VERSION}")
    lo_p, hi_p, lo_t, hi_t = (float(x) for x in parts[2:])
    return AxisLimits(lo_p, hi_p), AxisLimits(lo_t, hi_t)


def _intersect(a: AxisLimits, b: AxisLimits) -> AxisLimits:
    return AxisLimits(max(a.min_deg, b.min_deg), min(a.max_deg, b.max_deg))


class AsciiServoDriver:
    """`ServoDriver` over the ASCII protocol. Angles are clamped to the intersection of `pan_limits` /
    `tilt_limits` and the limits the board announces in its hello. Raises ServoError if the port cannot
    be opened or no valid hello arrives within boot_timeout_s (s)."""

    def __init__(
        self,
        path: str,
        baud: int = 115200,
        timeout_s: float = 0.3,
        boot_timeout_s: float = 2.5,
        pan_limits: AxisLimits = DEFAULT_PAN_LIMITS,
        tilt_limits: AxisLimits = DEFAULT_TILT_LIMITS,
        reconnect_interval_s: float = 1.0,
        clock: Callable[[], float] = time.monotonic,
    ):
        self.link = SerialLink(path, baud, timeout_s, "servo board", reconnect_interval_s, clock)
        self._host_limits = (pan_limits, tilt_limits)
        self.pan_limits, self.tilt_limits = pan_limits, tilt_limits
        self.link.open()
        deadline = time.monotonic() + boot_timeout_s
        while True:  # the board may be rebooting after the port opened (DTR reset)
            try:
                if self._hello():
                    break
            except ValueError as exc:
                self.link.close()
                raise ServoError(f"{path}: {exc}") from None
            if time.monotonic() >= deadline:
                fault = self.link.fault
                self.link.close()
                raise ServoError(f"{fault} (no hello within {boot_timeout_s:g} s)")
        self.link.on_reopen = self._rehello

    @property
    def fault(self) -> str | None:
        """None when healthy, else a one-line reason (see tracker.servo.base)."""
        return self.link.fault

    def command(self, pan_deg: float, tilt_deg: float) -> None:
        """`P <pan> <tilt>` with clamped angles; a missing/`ERR` reply sets `fault`."""
        pan, tilt = self.pan_limits.clamp(pan_deg), self.tilt_limits.clamp(tilt_deg)
        reply = self.link.request_line(f"P {pan:.2f} {tilt:.2f}")
        if reply is not None and reply != "OK":
            self._bad_reply(reply)

    def read_position(self) -> GimbalState | None:
        """`Q` -> the board's last commanded angles, or None while faulted."""
        reply = self.link.request_line("Q")
        if reply is None:
            return None
        parts = reply.split()
        try:
            if len(parts) != 3 or parts[0] != "POS":
                raise ValueError
            return GimbalState(float(parts[1]), float(parts[2]))
        except ValueError:
            self._bad_reply(reply)
            return None

    def detach(self) -> None:
        """`D`: stop the servo pulses (the next command re-attaches)."""
        reply = self.link.request_line("D")
        if reply is not None and reply != "OK":
            self._bad_reply(reply)

    def close(self) -> None:
        self.link.close()

    def _bad_reply(self, reply: str) -> None:
        if reply.startswith("ERR"):
            self.link.fault = f"servo board error: {reply[3:].strip() or 'unspecified'}"
        else:
            self.link.fault = f"unexpected reply from servo board: {reply[:40]!r}"

    def _hello(self) -> bool:
        """Send H; on a valid reply adopt the board's limits. ValueError for a wrong board/version."""
        reply = self.link.request_line("H")
        if reply is None:
            return False
        pan, tilt = parse_hello(reply)
        self.pan_limits = _intersect(self._host_limits[0], pan)
        self.tilt_limits = _intersect(self._host_limits[1], tilt)
        return True

    def _rehello(self) -> bool:
        try:
            return self._hello()
        except ValueError as exc:
            self.link.fault = f"after reconnecting: {exc}"
            return False
