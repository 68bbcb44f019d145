"""Camera faults in the runtime: a source that raises, stalls or comes back. The fault is in the status
within 1 s (a stall: once no frame came for 1 s), reads are retried with a growing back-off, tracking
resumes within 2 s of the source's return, and no thread dies. The source is the simulated rig wrapped
in a switch the test throws; the status is checked against the server's /api/status schema."""

from __future__ import annotations

import threading
import time
from typing import Any

import pytest

from server.schemas import Status
from server.services.monitor import Monitor
from tmeye.runtime import Runtime, RuntimeConfig
from tmeye.runtime.faults import SourceHealth
from tracker.frames import StereoFrame


class Switch:
    """A frame source that passes frames through, raises, or blocks, as the test says."""

    def __init__(self, inner: Any):
        self.inner, self.mode = inner, "ok"
        self.release = threading.Event()
        self.attempts: list[float] = []

    def read(self) -> StereoFrame | None:
        self.attempts.append(time.monotonic())
        if self.mode == "raise":
            raise OSError("camera unplugged")
        if self.mode == "stall":
            self.release.wait(30)
        return self.inner.read()  # type: ignore[no-any-return]

    def close(self) -> None:
        self.inner.close()


def _status(rt: Runtime) -> Status:
    st = rt.status()
    st.update(Monitor().figures(60.0), servo={"configured": False})
    return Status.model_validate(st)


def _source_fault(rt: Runtime) -> str | None:
    return next((f["message"] for f in rt.status()["faults"] if f["kind"] == "source"), None)


def _until(cond: Any, timeout: float) -> float | None:
    """Seconds until cond() held, or None after timeout."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if cond():
            return time.monotonic() - t0
        time.sleep(0.01)
    return None


@pytest.fixture
def runtime() -> Any:
    rt = Runtime(RuntimeConfig(source="sim", scenario="endless", servo=None, realtime=True))
    rt.start()
    assert rt.comp is not None
    switch = Switch(rt.comp.source)
    rt.comp.source = switch  # type: ignore[assignment]
    assert _until(lambda: rt.frames > 5, 30) is not None
    yield rt, switch
    switch.release.set()
    rt.stop()


def test_a_source_that_raises_then_returns(runtime: Any) -> None:
    rt, switch = runtime
    assert _source_fault(rt) is None and _status(rt).faults == []
    switch.mode = "raise"
    seen = _until(lambda: _source_fault(rt) is not None, 5)
    assert seen is not None and seen <= 1.0, seen
    assert "OSError: camera unplugged" in (_source_fault(rt) or "")
    time.sleep(3.0)
    gaps = [b - a for a, b in zip(switch.attempts[-6:], switch.attempts[-5:], strict=False)]
    assert all(0.05 <= g <= 1.5 for g in gaps), gaps  # retried, backing off to about 1 s, never a busy loop
    st = _status(rt)
    assert st.state == "running" and rt.running and st.source_faults == 1
    assert any(f.kind == "source" for f in st.faults)
    frames = rt.frames
    switch.mode = "ok"
    back = _until(lambda: rt.frames > frames + 2 and _source_fault(rt) is None, 5)
    assert back is not None and back <= 2.0, back
    assert rt.running and rt.latest is not None and rt.latest.frame_no > 0


def test_a_stalled_source_is_a_fault_until_it_returns(runtime: Any) -> None:
    rt, switch = runtime
    skipped = rt.skipped
    switch.mode = "stall"
    t0 = time.monotonic()
    seen = _until(lambda: _source_fault(rt) is not None, 5)
    assert seen is not None and seen <= 1.0 + 1.0, seen  # a stall is a fault once 1 s passed without a frame
    assert "stalled" in (_source_fault(rt) or "") and time.monotonic() - t0 >= 1.0
    time.sleep(1.0)
    assert _status(rt).state == "running"
    frames = rt.frames
    switch.mode = "ok"
    switch.release.set()
    back = _until(lambda: rt.frames > frames + 2 and _source_fault(rt) is None, 5)
    assert back is not None and back <= 2.0, back
    assert rt.running and rt.status()["source_faults"] == 1
    assert rt.skipped - skipped < 10  # the stall's missed frames are not counted as skipped


def test_source_health_backoff_and_stall_rules() -> None:
    now = [0.0]
    h = SourceHealth(retry_s=0.1, retry_max_s=1.0, stall_s=1.0, clock=lambda: now[0])
    waits = []
    for _ in range(6):
        h.reading()
        waits.append(h.failed(RuntimeError("gone")))
    assert waits == [0.1, 0.2, 0.4, 0.8, 1.0, 1.0] and h.faults == 1 and h.fault() == "RuntimeError: gone"
    h.reading()
    assert h.read() and h.fault() is None and h.failures == 0
    h.reading()
    now[0] += 0.5
    assert h.fault() is None  # a read in progress for 0.5 s is no stall yet
    now[0] += 0.6
    assert h.fault() == "source stalled: no frame for 1.1 s"
    assert h.read() and h.faults == 2 and h.fault() is None
    h.reading()
    assert h.failed(OSError()) == 0.1 and h.fault() == "OSError"  # the back-off starts again
