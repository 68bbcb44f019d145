"""Server events (calibration progress, later alarms) broadcast to `/ws/events` clients. Each client has
a bounded queue that drops its oldest event when full; publishing never waits. Event-loop side only,
except `publish_threadsafe`."""

from __future__ import annotations

import asyncio
import time
from collections import deque
from typing import Any


class EventClient:
    def __init__(self, maxsize: int):
        self.items: deque[dict[str, Any]] = deque(maxlen=maxsize)
        self.ready = asyncio.Event()
        self.dropped = 0

    def put(self, ev: dict[str, Any]) -> None:
        if len(self.items) == self.items.maxlen:
            self.dropped += 1
        self.items.append(ev)
        self.ready.set()

    async def next_batch(self) -> list[dict[str, Any]]:
        await self.ready.wait()
        self.ready.clear()
        batch = list(self.items)
        self.items.clear()
        return batch


class EventBus:
    def __init__(self, loop: asyncio.AbstractEventLoop, maxsize: int = 64):
        self.loop = loop
        self.maxsize = maxsize
        self.clients: set[EventClient] = set()

    def subscribe(self) -> EventClient:
        c = EventClient(self.maxsize)
        self.clients.add(c)
        return c

    def unsubscribe(self, c: EventClient) -> None:
        self.clients.discard(c)

    def publish(self, kind: str, **data: Any) -> None:
        ev = {"type": kind, "at": round(time.time(), 6), **data}
        for c in list(self.clients):
            c.put(ev)

    def publish_threadsafe(self, kind: str, **data: Any) -> None:
        if not self.loop.is_closed():
            self.loop.call_soon_threadsafe(lambda: self.publish(kind, **data))
