"""The health of a frame source, as the runtime's worker sees it (no I/O here; times from `clock`).

A read that raises is a fault at once; the worker retries after `backoff()`, which doubles from
`retry_s` to `retry_max_s`, so a source that comes back is read again within `retry_max_s`. A read that
blocks longer than `stall_s` is a fault while it blocks (`fault()` says so to any thread). The fault
ends with the next frame.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable

log = logging.getLogger("tmeye.runtime")


class SourceHealth:
    def __init__(self, retry_s: float = 0.1, retry_max_s: float = 1.0, stall_s: float = 1.0,
                 clock: Callable[[], float] = time.monotonic):
        self.retry_s, self.retry_max_s, self.stall_s, self.clock = retry_s, retry_max_s, stall_s, clock
        self.error: str | None = None  # the last failed read's message, while failing
        self.failures = 0  # consecutive failed reads
        self.faults = 0  # faults (a failure or a stall) since the start
        self._backoff = retry_s
        self._since: float | None = None  # start of the current fault
        self._reading_since: float | None = None

    def reading(self) -> None:
        """The worker starts a read."""
        self._reading_since = self.clock()

    def failed(self, exc: BaseException) -> float:
        """The read raised: record it; the seconds to wait before the next read."""
        self._reading_since = None
        if self._since is None:
            self._since = self.clock()
            self.faults += 1
            log.warning("source failed: %s (retrying)", exc)
        self.failures += 1
        text = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__
        self.error = text.splitlines()[0][:300]
        wait, self._backoff = self._backoff, min(2 * self._backoff, self.retry_max_s)
        return wait

    def read(self) -> bool:
        """A frame came (or the source ended): True when this ends a fault (a failure or a stall)."""
        now = self.clock()
        started, self._reading_since = self._reading_since, None
        stalled = started is not None and now - started > self.stall_s
        ended = self._since is not None or stalled
        if ended:
            since = self._since if self._since is not None else started
            if self._since is None:
                self.faults += 1
            log.warning("source back after %.1f s (%d failed reads)", now - (since or now), self.failures)
        self.error, self._since, self.failures, self._backoff = None, None, 0, self.retry_s
        return ended

    def fault(self) -> str | None:
        """The current fault in one line, or None (safe from any thread)."""
        if self.error is not None:
            return self.error
        started = self._reading_since
        if started is not None and (waited := self.clock() - started) > self.stall_s:
            return f"source stalled: no frame for {waited:.1f} s"
        return None
