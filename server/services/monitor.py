"""Server health figures: event-loop lag (a task that asks to sleep 50 ms and measures how late it wakes)
and capture-to-WebSocket-send latency, each over a sliding window, as percentiles in milliseconds."""

from __future__ import annotations

import asyncio
import threading
import time

import numpy as np


def percentiles(values: list[float] | np.ndarray) -> dict[str, float | int | None]:
    """{"n", "p50", "p99", "max"} of values (ms), None when empty."""
    v = np.sort(np.asarray(values, dtype=np.float64))
    if not v.size:
        return {"n": 0, "p50": None, "p99": None, "max": None}

    def q(p: float) -> float:
        return round(float(v[min(v.size - 1, int(round(p * (v.size - 1))))]), 3)
    return {"n": int(v.size), "p50": q(0.5), "p99": q(0.99), "max": round(float(v[-1]), 3)}


class Samples:
    """The last `size` (time, value) samples in two preallocated arrays: the memory is taken once, at
    start, however long the server runs (a deque of tuples grew by about 45 MB while it filled)."""

    def __init__(self, size: int):
        self.t = np.full(size, -np.inf)  # monotonic s; -inf: empty
        self.v = np.full(size, 0.0)  # written now: its pages count from the start, not as the ring fills
        self.n = 0  # samples added since the start

    def add(self, t: float, value: float) -> None:
        i = self.n % self.t.size
        self.t[i], self.v[i] = t, value
        self.n += 1

    def __len__(self) -> int:
        return min(self.n, self.t.size)

    def since(self, t0: float) -> np.ndarray:
        """A copy of the values of the samples taken at t0 or later."""
        return self.v[self.t >= t0].copy()


class Monitor:
    """window: samples kept per figure (at 20 lag samples per second, 1200 is a minute)."""

    def __init__(self, window: int = 12000, send_window: int = 200000, period_s: float = 0.05):
        self.period_s = period_s
        self.lag_ms = Samples(window)
        self.send_ms = Samples(send_window)
        self.delivery_ms = Samples(send_window)
        # the samples are added on the event loop and read by the status route in the thread pool: the
        # lock keeps a reader from seeing a time whose value is not written yet
        self._lock = threading.Lock()

    async def run(self) -> None:
        while True:
            t0 = time.perf_counter()
            await asyncio.sleep(self.period_s)
            t1 = time.perf_counter()
            with self._lock:
                self.lag_ms.add(time.monotonic(), max(0.0, (t1 - t0 - self.period_s) * 1e3))

    def sent(self, captured_at: float, processed_at: float) -> None:
        """A telemetry message went out: capture -> send, and the part after the tracker was done."""
        now, mono = time.time(), time.monotonic()
        with self._lock:
            self.send_ms.add(mono, (now - captured_at) * 1e3)
            self.delivery_ms.add(mono, (now - processed_at) * 1e3)

    def figures(self, window_s: float = 60.0) -> dict[str, dict[str, float | int | None]]:
        """Percentiles of the samples of the last window_s seconds (the window holds at most 10 minutes of lag
        samples and 200,000 sends)."""
        since = time.monotonic() - window_s
        with self._lock:  # only the copies under the lock; the sorting after it
            lag, send, delivery = (s.since(since) for s in (self.lag_ms, self.send_ms, self.delivery_ms))
        return {"event_loop_lag_ms": percentiles(lag), "ws_send_latency_ms": percentiles(send),
                "ws_delivery_ms": percentiles(delivery)}
