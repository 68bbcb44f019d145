"""WebSockets: `/ws/telemetry` (one JSON message per frame) and `/ws/events` (calibration progress and
other server events). Each client has its own bounded queue that drops the oldest message: a client that
reads slowly, or never, holds up no one else. Authenticated by the session cookie or a bearer header."""

from __future__ import annotations

import asyncio
import contextlib

from fastapi import APIRouter, HTTPException, WebSocket, WebSocketDisconnect

from server.context import AppContext
from server.deps import websocket_principal

router = APIRouter(tags=["telemetry"])


async def _accept(ws: WebSocket) -> AppContext | None:
    ctx: AppContext = ws.app.state.ctx
    try:
        await asyncio.to_thread(websocket_principal, ws, ctx)
    except HTTPException as exc:  # accepted, then closed with 1008 and the reason: browsers see why
        await ws.accept()
        await ws.close(code=1008, reason=str(exc.detail)[:120])
        return None
    await ws.accept()
    return ctx


async def _drain_client(ws: WebSocket) -> None:
    """Read (and ignore) what the client sends, so a close is noticed."""
    with contextlib.suppress(WebSocketDisconnect, RuntimeError):
        while True:
            await ws.receive_text()


@router.websocket("/ws/telemetry")
async def telemetry_ws(ws: WebSocket) -> None:
    ctx = await _accept(ws)
    if ctx is None:
        return
    loop = asyncio.get_running_loop()
    ready = asyncio.Event()
    sub = ctx.runtime.hub.subscribe(maxsize=ctx.settings.ws_queue,
                                    notify=lambda: loop.call_soon_threadsafe(ready.set), name="ws", first=True)
    reader = asyncio.create_task(_drain_client(ws))
    reader.add_done_callback(lambda _t: ready.set())
    try:
        while not reader.done():
            await ready.wait()
            ready.clear()
            for ev in sub.drain():
                await ws.send_text(ev.telemetry_json)
                ctx.monitor.sent(ev.captured_at, ev.done_at)
            if sub.closed:
                break
    except (WebSocketDisconnect, RuntimeError, OSError):
        pass
    finally:
        ctx.runtime.hub.unsubscribe(sub)
        reader.cancel()
        with contextlib.suppress(Exception):
            await ws.close()


@router.websocket("/ws/events")
async def events_ws(ws: WebSocket) -> None:
    ctx = await _accept(ws)
    if ctx is None:
        return
    client = ctx.events.subscribe()
    reader = asyncio.create_task(_drain_client(ws))
    reader.add_done_callback(lambda _t: client.ready.set())
    try:
        while not reader.done():
            for ev in await client.next_batch():
                await ws.send_json(ev)
    except (WebSocketDisconnect, RuntimeError, OSError):
        pass
    finally:
        ctx.events.unsubscribe(client)
        reader.cancel()
        with contextlib.suppress(Exception):
            await ws.close()
