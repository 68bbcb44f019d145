"""Serial servo drivers against simulated devices on real pseudo-terminals.

Each device runs in a thread on a pty master; the driver opens a symlink to the slave (like a udev
/dev/serial/by-id link). "Unplugging" closes the pty (the driver's I/O then fails); "re-plugging"
creates a new pty and re-points the symlink, so the driver's reopen of the same path finds it.
"""

from __future__ import annotations

import os
import select
import threading
import tty
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from tracker.frames import GimbalState
from tracker.servo import ServoError, open_servo
from tracker.servo.ascii import AsciiServoDriver
from tracker.servo.maestro import AxisCalibration, MaestroConfig, MaestroDriver, encode

Handler = Callable[[bytes], bytes]


class PtyDevice:
    """A simulated serial device: `handler(received bytes) -> reply bytes` runs on the pty master."""

    def __init__(self, link: Path, handler: Handler):
        self.link, self.handler = link, handler
        self.wire = bytearray()  # everything the driver sent, across re-plugs
        self.answering = True
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.plug()

    def plug(self) -> None:
        self.master, self.slave = os.openpty()
        tty.setraw(self.master)  # no echo, no line editing on the device side
        tmp = self.link.with_suffix(".new")
        tmp.unlink(missing_ok=True)
        tmp.symlink_to(os.ttyname(self.slave))
        os.replace(tmp, self.link)
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def unplug(self) -> None:
        if self._stop.is_set():
            return  # already unplugged
        self._stop.set()
        assert self._thread is not None
        self._thread.join()
        os.close(self.master)
        os.close(self.slave)

    def _run(self) -> None:
        while not self._stop.is_set():
            ready, _, _ = select.select([self.master], [], [], 0.02)
            if not ready:
                continue
            try:
                data = os.read(self.master, 4096)
            except OSError:
                return
            self.wire += data
            if self.answering:
                reply = self.handler(data)
                if reply:
                    os.write(self.master, reply)


class FakeMaestro:
    """Compact protocol: targets, speed, acceleration, get position, get errors."""

    def __init__(self) -> None:
        self.targets = {0: 6000, 1: 6000}  # quarter-µs
        self.speed: dict[int, int] = {}
        self.accel: dict[int, int] = {}
        self.errors = 0
        self._buf = b""

    def __call__(self, data: bytes) -> bytes:
        self._buf += data
        out = b""
        while self._buf:
            cmd = self._buf[0]
            if cmd in (0x84, 0x87, 0x89):
                if len(self._buf) < 4:
                    break
                ch, value = self._buf[1], self._buf[2] | self._buf[3] << 7
                {0x84: self.targets, 0x87: self.speed, 0x89: self.accel}[cmd][ch] = value
                self._buf = self._buf[4:]
            elif cmd == 0x90:
                if len(self._buf) < 2:
                    break
                out += self.targets[self._buf[1]].to_bytes(2, "little")
                self._buf = self._buf[2:]
            elif cmd == 0xA1:
                out += self.errors.to_bytes(2, "little")
                self.errors = 0
                self._buf = self._buf[1:]
            else:
                self.errors |= 1 << 4  # serial protocol error
                self._buf = self._buf[1:]
        return out


class FakeBoard:
    """The ASCII protocol as firmware/arduino/tmeye_servo implements it (limits ±90, -30..80)."""

    def __init__(self) -> None:
        self.pan = self.tilt = 0.0
        self._buf = b""

    def __call__(self, data: bytes) -> bytes:
        self._buf += data
        out = b""
        while b"\n" in self._buf:
            raw, self._buf = self._buf.split(b"\n", 1)
            line = raw.decode().strip()
            if line:
                out += (self.handle(line) + "\n").encode()
        return out

    def handle(self, line: str) -> str:
        parts = line.split()
        if parts == ["H"]:
            return "TMEYE-SERVO 1 -90 90 -30 80"
        if parts == ["Q"]:
            return f"POS {self.pan:.2f} {self.tilt:.2f}"
        if parts[0] == "P":
            try:
                pan, tilt = (float(x) for x in parts[1:])
            except ValueError:
                return "ERR bad number"
            self.pan, self.tilt = min(max(pan, -90.0), 90.0), min(max(tilt, -30.0), 80.0)
            return "OK"
        return "ERR unknown command"


class Clock:
    def __init__(self) -> None:
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


@pytest.fixture
def maestro(tmp_path: Path) -> Iterator[tuple[PtyDevice, FakeMaestro]]:
    fake = FakeMaestro()
    dev = PtyDevice(tmp_path / "ttyMaestro", fake)
    yield dev, fake
    dev.unplug()


@pytest.fixture
def board(tmp_path: Path) -> Iterator[tuple[PtyDevice, FakeBoard]]:
    fake = FakeBoard()
    dev = PtyDevice(tmp_path / "ttyBoard", fake)
    yield dev, fake
    dev.unplug()


def test_maestro_encoding_matches_the_pololu_example() -> None:
    assert encode(0x84, 2, 6000) == bytes([0x84, 0x02, 0x70, 0x2E])  # 1500 µs on channel 2
    cal = AxisCalibration(0, center_us=1500.0, us_per_deg=10.0, min_us=1000.0, max_us=2000.0)
    assert cal.to_us(20.0) == 1700.0 and cal.to_us(80.0) == 2000.0 and cal.to_deg(1700.0) == 20.0


def test_maestro_bytes_on_the_wire_and_replies(maestro: tuple[PtyDevice, FakeMaestro]) -> None:
    dev, fake = maestro
    cfg = MaestroConfig(speed=40, acceleration=5)
    drv = MaestroDriver(str(dev.link), config=cfg, timeout_s=0.2)
    setup = encode(0x87, 0, 40) + encode(0x89, 0, 5) + encode(0x87, 1, 40) + encode(0x89, 1, 5) + b"\xa1"
    assert bytes(dev.wire) == setup and fake.speed == {0: 40, 1: 40} and fake.accel == {0: 5, 1: 5}
    dev.wire.clear()
    drv.command(9.0, -4.5)
    us_pan, us_tilt = 1500 + 9.0 * 2000 / 180, 1500 - 4.5 * 2000 / 180
    expected = encode(0x84, 0, round(4 * us_pan)) + encode(0x84, 1, round(4 * us_tilt)) + b"\xa1"
    assert bytes(dev.wire) == expected and drv.fault is None
    pos = drv.read_position()
    assert pos is not None
    assert pos.pan_deg == pytest.approx(9.0, abs=0.03) and pos.tilt_deg == pytest.approx(-4.5, abs=0.03)
    fake.errors = 1 << 4 | 1 << 5
    drv.command(0.0, 0.0)
    assert drv.fault == "Maestro reported errors 0x0030: serial protocol, serial timeout"
    drv.command(0.0, 0.0)
    assert drv.fault is None and drv.last_errors == 0
    drv.close()


def test_maestro_not_answering_is_a_clear_error(maestro: tuple[PtyDevice, FakeMaestro]) -> None:
    dev, _ = maestro
    dev.answering = False
    with pytest.raises(ServoError, match=r"^no reply from Maestro on .* within 0.1 s \(is it a Maestro"):
        MaestroDriver(str(dev.link), timeout_s=0.1)
    dev.answering = True
    drv = MaestroDriver(str(dev.link), timeout_s=0.1)
    dev.answering = False  # goes silent mid-run: a fault, not an exception
    drv.command(1.0, 1.0)
    assert drv.fault is not None and drv.fault.startswith("no reply from Maestro")
    assert drv.read_position() is None
    dev.answering = True  # answers again: healthy at the next exchange (the lost command is not replayed)
    assert drv.read_position() == GimbalState(0.0, 0.0) and drv.fault is None
    drv.command(1.0, 1.0)
    pos = drv.read_position()
    assert pos is not None and pos.pan_deg == pytest.approx(1.0, abs=0.03) and drv.fault is None
    drv.close()


def test_maestro_port_vanishes_then_comes_back(maestro: tuple[PtyDevice, FakeMaestro]) -> None:
    dev, fake = maestro
    clock = Clock()
    drv = MaestroDriver(str(dev.link), timeout_s=0.2, reconnect_interval_s=1.0, clock=clock)
    dev.unplug()
    drv.command(5.0, 5.0)
    assert drv.fault is not None and "lost" in drv.fault and not drv.link.is_open
    drv.command(5.0, 5.0)  # too soon to retry: no reopen attempt
    assert drv.link.reopen_attempts == 0
    clock.t += 1.5
    drv.command(5.0, 5.0)  # retried, but the device is still gone
    assert drv.link.reopen_attempts == 1 and drv.fault is not None and "unavailable" in drv.fault
    fake.targets = {0: 6000, 1: 6000}
    dev.plug()
    dev.wire.clear()
    clock.t += 1.5
    drv.command(5.0, 5.0)  # reopened: setup is sent again, then the command
    assert drv.link.reopen_attempts == 2 and drv.fault is None
    assert (
        bytes(dev.wire).startswith(encode(0x87, 0, 0))
        and encode(0x84, 0, round(4 * (1500 + 5 * 2000 / 180))) in dev.wire
    )
    drv.close()


def test_ascii_protocol_on_the_wire(board: tuple[PtyDevice, FakeBoard]) -> None:
    dev, fake = board
    drv = AsciiServoDriver(str(dev.link), timeout_s=0.2)
    assert bytes(dev.wire) == b"H\n"
    assert drv.pan_limits.max_deg == 90.0 and drv.tilt_limits.min_deg == -30.0  # the board's limits
    drv.command(12.5, -3.0)
    assert drv.read_position() == GimbalState(12.5, -3.0)
    drv.command(200.0, -60.0)  # clamped on the host to the board's limits
    assert bytes(dev.wire).endswith(b"P 12.50 -3.00\nQ\nP 90.00 -30.00\n")
    assert drv.fault is None
    fake.handle = lambda line: "ERR bad number"  # type: ignore[method-assign]
    drv.command(1.0, 1.0)
    assert drv.fault == "servo board error: bad number"
    drv.close()


def test_ascii_silent_board_then_recovery(board: tuple[PtyDevice, FakeBoard]) -> None:
    dev, _ = board
    dev.answering = False
    with pytest.raises(ServoError, match=r"no reply from servo board .* \(no hello within 0.3 s\)"):
        AsciiServoDriver(str(dev.link), timeout_s=0.1, boot_timeout_s=0.3)
    dev.answering = True
    drv = AsciiServoDriver(str(dev.link), timeout_s=0.1)
    dev.answering = False
    drv.command(3.0, 4.0)
    assert drv.fault is not None and drv.fault.startswith("no reply from servo board")
    dev.answering = True
    drv.command(3.0, 4.0)
    assert drv.fault is None and drv.read_position() == GimbalState(3.0, 4.0)
    drv.close()


def test_ascii_port_vanishes_then_comes_back(board: tuple[PtyDevice, FakeBoard]) -> None:
    dev, _ = board
    clock = Clock()
    drv = AsciiServoDriver(str(dev.link), timeout_s=0.2, reconnect_interval_s=0.5, clock=clock)
    dev.unplug()
    assert drv.read_position() is None
    assert drv.fault is not None and "lost" in drv.fault
    drv.command(1.0, 2.0)  # dropped, no exception, no reopen yet
    assert drv.link.reopen_attempts == 0
    dev.plug()
    dev.wire.clear()
    clock.t += 0.6
    drv.command(1.0, 2.0)
    assert drv.fault is None and bytes(dev.wire) == b"H\nP 1.00 2.00\n"  # hello again, then the command
    assert drv.read_position() == GimbalState(1.0, 2.0)
    drv.close()


def test_bad_urls_and_missing_ports(tmp_path: Path) -> None:
    cases = {
        "bogus:/dev/ttyS0": "unknown scheme 'bogus'",
        "maestro:": "no serial port given",
        "ascii:/dev/x?speed=3": r"unknown option\(s\) speed",
        "ascii:/dev/x?baud=fast": "is not a number",
        f"maestro:{tmp_path}/nothing": "cannot open Maestro port",
        f"ascii:{tmp_path}/nothing?baud=9600": "cannot open servo board port",
    }
    for url, message in cases.items():
        with pytest.raises(ServoError, match=message) as info:
            open_servo(url)
        assert "\n" not in str(info.value)


def test_open_servo_returns_working_serial_drivers(
    maestro: tuple[PtyDevice, FakeMaestro], board: tuple[PtyDevice, FakeBoard]
) -> None:
    m = open_servo(f"maestro:{maestro[0].link}?baud=57600&timeout=0.2")
    a = open_servo(f"ascii:{board[0].link}?timeout=0.2")
    assert isinstance(m, MaestroDriver) and isinstance(a, AsciiServoDriver)
    assert m.link.baud == 57600
    for drv in (m, a):
        drv.command(10.0, 20.0)
        pos = drv.read_position()
        assert pos is not None and pos.pan_deg == pytest.approx(10.0, abs=0.03) and drv.fault is None
        drv.close()
