"""The longest interval between two frames the runtime published, over a recent window.

A fixed ring of one slot per second of the monotonic clock (an hour by default) holds each second's longest
interval, so the memory never grows however long the runtime runs."""

from __future__ import annotations

import numpy as np


class StallLog:
    """Per-second maxima of the interval between consecutive frames (s), for the last `seconds` seconds."""

    def __init__(self, seconds: int = 3600) -> None:
        self._second = np.full(seconds, -1, np.int64)  # which second of the monotonic clock a slot holds
        self._gap = np.zeros(seconds, np.float64)
        self._last: float | None = None

    def frame(self, now: float) -> None:
        """A frame was published at `now` (time.monotonic() s)."""
        if self._last is not None:
            s = int(now)
            i = s % len(self._second)
            if self._second[i] != s:
                self._second[i], self._gap[i] = s, 0.0
            self._gap[i] = max(self._gap[i], now - self._last)
        self._last = now

    def pause(self) -> None:
        """The source paused on purpose (or the runtime restarted): the next interval is not a stall."""
        self._last = None

    def longest_ms(self, window_s: float, now: float) -> float | None:
        """The longest interval (ms) between frames that ended in the last `window_s` seconds, or that is
        still open at `now`; None before the second frame."""
        recent = self._second > int(now) - max(int(np.ceil(window_s)), 1)
        gaps = self._gap[recent]
        open_gap = 0.0 if self._last is None else now - self._last
        if not gaps.size and self._last is None:
            return None
        return round(1e3 * max(float(gaps.max()) if gaps.size else 0.0, open_gap), 1)
