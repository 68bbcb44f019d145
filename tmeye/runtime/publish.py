"""Publishing frame results to many subscribers without ever blocking the producer.

Each `Subscription` is a bounded queue that drops its oldest item when full and counts what it dropped;
`Hub.publish` puts the item into every subscription and calls each one's `notify` callback (for an
asyncio consumer, a `loop.call_soon_threadsafe` wake-up). Nothing a subscriber does (reading slowly,
never reading, raising in its callback) can stall the publisher or the other subscribers.
"""

from __future__ import annotations

import logging
import threading
from collections import deque
from collections.abc import Callable
from typing import Any, Generic, TypeVar

T = TypeVar("T")
log = logging.getLogger("tmeye.runtime")


class Subscription(Generic[T]):
    """A bounded drop-oldest queue. `put` never blocks; `get(timeout)` waits in a consumer thread;
    `drain()` takes everything without waiting (asyncio consumers, after their notify)."""

    def __init__(self, maxsize: int, notify: Callable[[], Any] | None = None, name: str = "",
                 first: bool = False):
        if maxsize < 1:
            raise ValueError(f"a subscription holds at least one item, got maxsize={maxsize}")
        self.name = name
        self.first = first  # put and notified before the subscriptions without (Hub.subscribe)
        self.maxsize = maxsize
        self.notify = notify
        self.dropped = 0
        self.delivered = 0
        self._items: deque[T] = deque()
        self._cond = threading.Condition()
        self.closed = False

    def put(self, item: T) -> None:
        with self._cond:
            if len(self._items) >= self.maxsize:
                self._items.popleft()
                self.dropped += 1
            self._items.append(item)
            self._cond.notify()

    def get(self, timeout: float | None = None) -> T | None:
        """The oldest item, waiting up to `timeout` s (None: until one comes or the subscription closes)."""
        with self._cond:
            if not self._items and not self.closed:
                self._cond.wait(timeout)
            if not self._items:
                return None
            self.delivered += 1
            return self._items.popleft()

    def drain(self) -> list[T]:
        with self._cond:
            items = list(self._items)
            self._items.clear()
            self.delivered += len(items)
            return items

    def close(self) -> None:
        with self._cond:
            self.closed = True
            self._cond.notify_all()

    def __len__(self) -> int:
        return len(self._items)


class Hub(Generic[T]):
    """The set of subscriptions of one producer. Thread-safe."""

    def __init__(self) -> None:
        self._subs: list[Subscription[T]] = []  # those subscribed `first` ahead of the others
        self._lock = threading.Lock()

    def subscribe(self, maxsize: int = 4, notify: Callable[[], Any] | None = None,
                  name: str = "", first: bool = False) -> Subscription[T]:
        """A new subscription. first: put and notified before those without (a consumer someone waits on,
        such as a telemetry WebSocket, is woken before the H.264 encoder takes the GIL for the frame)."""
        sub: Subscription[T] = Subscription(maxsize, notify, name, first)
        with self._lock:
            self._subs.insert(sum(1 for s in self._subs if s.first) if first else len(self._subs), sub)
        return sub

    def unsubscribe(self, sub: Subscription[T]) -> None:
        with self._lock:
            if sub in self._subs:
                self._subs.remove(sub)
        sub.close()

    @property
    def subscribers(self) -> int:
        return len(self._subs)

    def stats(self) -> list[dict[str, Any]]:
        """Per subscription: name, items waiting, delivered and dropped (a slow reader drops, no one waits)."""
        with self._lock:
            subs = list(self._subs)
        return [{"name": s.name, "queued": len(s), "delivered": s.delivered, "dropped": s.dropped} for s in subs]

    def publish(self, item: T) -> None:
        with self._lock:
            subs = list(self._subs)
        for sub in subs:
            sub.put(item)
            if sub.notify is not None:
                try:
                    sub.notify()
                except Exception:  # a consumer's wake-up failing (its loop closed) is its own problem
                    log.debug("subscriber %s: notify failed", sub.name, exc_info=True)

    def close(self) -> None:
        with self._lock:
            subs, self._subs = list(self._subs), []
        for sub in subs:
            sub.close()
