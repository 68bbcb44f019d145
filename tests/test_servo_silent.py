"""A servo that stops answering while its port stays open (a real pty whose fake Maestro goes silent), on a real
`tmeye serve`: the servo fault alarm within 1 s, cleared within 2 s once the device answers again, and tracking
goes on throughout (the frame count keeps rising)."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from fault_helpers import open_alarms
from server_helpers import Server, start_server
from test_servo_serial import FakeMaestro, PtyDevice


def wait_for(cond: Callable[[], Any], timeout: float) -> Any:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        v = cond()
        if v:
            return v
        time.sleep(0.05)
    raise AssertionError(f"not within {timeout} s")


@pytest.fixture
def silent_server(tmp_path: Path) -> Iterator[tuple[Server, PtyDevice]]:
    dev = PtyDevice(tmp_path / "ttyMaestro", FakeMaestro())
    s = start_server(tmp_path / "data", "--servo", f"maestro:{dev.link}?timeout=0.3")
    yield s, dev
    s.stop()
    dev.unplug()


def test_silent_servo_raises_a_fault_within_1s_clears_within_2s_and_tracking_goes_on(
        silent_server: tuple[Server, PtyDevice]) -> None:
    server, dev = silent_server
    with server.as_admin() as c:
        def servo_alarm() -> list[dict[str, Any]]:
            return open_alarms(c, "fault:servo")
        time.sleep(2.0)
        assert servo_alarm() == []
        frame0 = c.get("/api/status").json()["frame"]
        t_off = time.time()
        dev.answering = False  # the port stays open; the device reads but no longer replies
        alarm = wait_for(servo_alarm, 5.0)[0]
        raised_after = alarm["activated_at"] - t_off
        assert raised_after <= 1.0, raised_after
        assert "no reply from Maestro" in alarm["message"], alarm
        time.sleep(2.0)
        frame1 = c.get("/api/status").json()["frame"]
        t_on = time.time()
        dev.answering = True
        cleared = wait_for(lambda: c.get(f"/api/alarms/{alarm['id']}").json()["cleared_at"], 5.0)
        cleared_after = cleared - t_on
        assert cleared_after <= 2.0, cleared_after
        time.sleep(1.0)
        frame2 = c.get("/api/status").json()["frame"]
        assert frame1 > frame0 + 40 and frame2 > frame1 + 20, (frame0, frame1, frame2)  # tracking went on
        print(f"silent servo: fault raised {raised_after:.3f} s after it went silent, cleared {cleared_after:.3f} s "
              f"after it answered again; frames {frame0} -> {frame1} -> {frame2}")
