"""Server health figures: event-loop lag (a task that asks to sleep 50 ms and measures how late it wakes)
and capture-to-WebSocket-send latency, each over a sliding window, as percentiles in milliseconds."""

from __future__ import annotations

import asyncio
import threading
import time
from collections import deque


def percentiles(values: list[float]) -> dict[str, float | int | None]:
    """{"n", "p50", "p99", "max"} of values (ms), None when empty."""
    v = sorted(values)
    if not v:
        return {"n": 0, "p50": None, "p99": None, "max": None}
    def q(p: float) -> float:
        return round(v[min(len(v) - 1, int(round(p * (len(v) - 1))))], 3)
    return {"n": len(v), "p50": q(0.5), "p99": q(0.99), "max": round(v[-1], 3)}


class Monitor:
    """window: samples kept per figure (at 20 lag samples per second, 1200 is a minute)."""

    def __init__(self, window: int = 12000, send_window: int = 200000, period_s: float = 0.05):
        self.period_s = period_s
        self.lag_ms: deque[tuple[float, float]] = deque(maxlen=window)  # (monotonic s, ms)
        self.send_ms: deque[tuple[float, float]] = deque(maxlen=send_window)
        self.delivery_ms: deque[tuple[float, float]] = deque(maxlen=send_window)
        # the samples are added on the event loop and read by the status route in the thread pool: copying a
        # deque while another thread appends raises "deque mutated during iteration" (a 500 of /api/status)
        self._lock = threading.Lock()

    async def run(self) -> None:
        while True:
            t0 = time.perf_counter()
            await asyncio.sleep(self.period_s)
            t1 = time.perf_counter()
            with self._lock:
                self.lag_ms.append((time.monotonic(), max(0.0, (t1 - t0 - self.period_s) * 1e3)))

    def sent(self, captured_at: float, processed_at: float) -> None:
        """A telemetry message went out: capture -> send, and the part after the tracker was done."""
        now, mono = time.time(), time.monotonic()
        with self._lock:
            self.send_ms.append((mono, (now - captured_at) * 1e3))
            self.delivery_ms.append((mono, (now - processed_at) * 1e3))

    def figures(self, window_s: float = 60.0) -> dict[str, dict[str, float | int | None]]:
        """Percentiles of the samples of the last window_s seconds (the window holds at most 10 minutes of lag
        samples and 200,000 sends)."""
        since = time.monotonic() - window_s
        with self._lock:  # only the copies under the lock; the sorting after it
            lag, send, delivery = list(self.lag_ms), list(self.send_ms), list(self.delivery_ms)
        return {"event_loop_lag_ms": percentiles([v for t, v in lag if t >= since]),
                "ws_send_latency_ms": percentiles([v for t, v in send if t >= since]),
                "ws_delivery_ms": percentiles([v for t, v in delivery if t >= since])}
