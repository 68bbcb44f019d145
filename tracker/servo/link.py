"""SerialLink: a serial port (pyserial) that reports faults instead of raising and reopens itself.

- `open()` (called once by a driver's constructor) raises ServoError if the port cannot be opened.
- After that, `write`, `request` and `request_line` never raise. A reply that does not arrive within
  `timeout_s` sets `fault` ("no reply ...") and keeps the port open (the device may answer again). An
  I/O error (the port vanished: USB unplugged, pty closed) sets `fault` ("port ... lost: ...") and closes
  the port; every later call first tries to reopen the same path, at most once per `reconnect_interval_s`
  (so a tracker calling at 30 Hz does not hammer the OS), then runs `on_reopen` (the driver's hello or
  setup) before going on. A successful exchange clears `fault`.
- Reopening the same *path* is what makes reconnection work with udev symlinks (/dev/serial/by-id/...,
  or /dev/ttyACM0 coming back) and in the tests (a symlink re-pointed to a new pseudo-terminal).
"""

from __future__ import annotations

import math
import termios
import time
from collections.abc import Callable

import serial

from tracker.servo.base import ServoError

_IO_ERRORS = (serial.SerialException, OSError, termios.error)


class SerialLink:
    """See the module docstring. `name` is the device name used in messages (e.g. 'Maestro')."""

    def __init__(
        self,
        path: str,
        baud: int,
        timeout_s: float,
        name: str,
        reconnect_interval_s: float = 1.0,
        clock: Callable[[], float] = time.monotonic,
    ):
        self.path, self.baud, self.timeout_s, self.name = path, baud, timeout_s, name
        self.reconnect_interval_s = reconnect_interval_s
        self.clock = clock
        self.fault: str | None = None
        self.on_reopen: Callable[[], bool] | None = None  # returns False if the device did not answer
        self.reopen_attempts = 0
        self._ser: serial.Serial | None = None
        self._last_attempt = -math.inf

    @property
    def is_open(self) -> bool:
        return self._ser is not None

    def open(self) -> None:
        """Open the port; raise ServoError (one line) if it is missing or unusable."""
        try:
            self._ser = self._open_port()
        except _IO_ERRORS as exc:
            raise ServoError(f"cannot open {self.name} port {self.path}: {_reason(exc)}") from None

    def close(self) -> None:
        """Close the port (idempotent); no reconnection is attempted until the next call."""
        ser, self._ser = self._ser, None
        if ser is None:
            return
        try:
            ser.close()
        except _IO_ERRORS:
            return  # the device is already gone: nothing left to release

    def write(self, data: bytes) -> bool:
        """Send bytes; False (and `fault` set) if the port is gone."""
        ser = self._ensure_open()
        if ser is None:
            return False
        try:
            ser.write(data)
            ser.flush()
        except _IO_ERRORS as exc:
            self._lost(exc)
            return False
        return True

    def request(self, data: bytes, n_reply: int) -> bytes | None:
        """Send `data`, return exactly `n_reply` reply bytes, or None on timeout / lost port."""
        ser = self._ensure_open()
        if ser is None:
            return None
        try:
            ser.reset_input_buffer()  # drop late replies to earlier requests
            ser.write(data)
            ser.flush()
            reply = bytes(ser.read(n_reply))
        except _IO_ERRORS as exc:
            self._lost(exc)
            return None
        if len(reply) < n_reply:
            self.fault = f"no reply from {self.name} on {self.path} within {self.timeout_s:g} s"
            return None
        self.fault = None
        return reply

    def request_line(self, line: str) -> str | None:
        """Send `line` + '\\n', return the reply line without its end, or None on timeout / lost port."""
        ser = self._ensure_open()
        if ser is None:
            return None
        try:
            ser.reset_input_buffer()
            ser.write(line.encode("ascii") + b"\n")
            ser.flush()
            raw = bytes(ser.read_until(b"\n"))
        except _IO_ERRORS as exc:
            self._lost(exc)
            return None
        if not raw.endswith(b"\n"):
            self.fault = f"no reply from {self.name} on {self.path} within {self.timeout_s:g} s"
            return None
        self.fault = None
        return raw.decode("ascii", errors="replace").strip()

    # --- internals ---------------------------------------------------------------------------------

    def _open_port(self) -> serial.Serial:
        return serial.Serial(self.path, self.baud, timeout=self.timeout_s, write_timeout=self.timeout_s)

    def _lost(self, exc: BaseException) -> None:
        self.fault = f"{self.name} port {self.path} lost: {_reason(exc)}"
        self.close()
        self._last_attempt = self.clock()  # the next reopen waits a full interval

    def _ensure_open(self) -> serial.Serial | None:
        """The open port, reopening it (rate-limited) if it was lost; None if it is still unavailable."""
        if self._ser is not None:
            return self._ser
        now = self.clock()
        if now - self._last_attempt < self.reconnect_interval_s:
            return None
        self._last_attempt = now
        self.reopen_attempts += 1
        try:
            self._ser = self._open_port()
        except _IO_ERRORS as exc:
            self.fault = f"{self.name} port {self.path} unavailable: {_reason(exc)}"
            return None
        if self.on_reopen is not None and not self.on_reopen():
            return None  # the device did not answer its setup: `fault` says why; try again next call
        return self._ser


def _reason(exc: BaseException) -> str:
    """A one-line reason from an exception."""
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__
