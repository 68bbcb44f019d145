"""The server's monitor is written on the event loop and read by the status route in the thread pool: reading
while the loop adds samples must never fail (it did: "deque mutated during iteration", a 500 of /api/status
in a soak, from iterating the lag samples in Python while the loop appended)."""

from __future__ import annotations

import asyncio
import contextlib
import threading
import time

from server.services.monitor import Monitor, Samples, percentiles


def test_figures_while_the_loop_adds_samples() -> None:
    m = Monitor(window=12000, period_s=0.0)  # lag samples as fast as the loop turns
    loop = asyncio.new_event_loop()
    task = loop.create_task(m.run())
    def spin() -> None:
        with contextlib.suppress(asyncio.CancelledError):
            loop.run_until_complete(task)

    t = threading.Thread(target=spin)
    t.start()
    try:
        deadline = time.monotonic() + 20
        while len(m.lag_ms) < 12000 and time.monotonic() < deadline:
            time.sleep(0.01)
        for _ in range(300):
            assert m.figures(600.0)["event_loop_lag_ms"]["n"] > 0
    finally:
        loop.call_soon_threadsafe(task.cancel)
        t.join()
        loop.close()


def test_samples_keep_the_last_window_in_fixed_memory() -> None:
    s = Samples(5)
    before = (s.t.nbytes + s.v.nbytes, s.t.ctypes.data)
    for i in range(12):
        s.add(float(i), 10.0 * i)
    assert len(s) == 5 and (s.t.nbytes + s.v.nbytes, s.t.ctypes.data) == before
    assert sorted(s.since(0.0).tolist()) == [70.0, 80.0, 90.0, 100.0, 110.0]  # the oldest were overwritten
    assert sorted(s.since(9.5).tolist()) == [100.0, 110.0]
    assert percentiles(s.since(0.0)) == {"n": 5, "p50": 90.0, "p99": 110.0, "max": 110.0}
    assert percentiles([])["p50"] is None
