"""Live video: WebRTC signalling (non-trickle offer/answer) and the MJPEG fallback."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator
from typing import Literal

from fastapi import APIRouter, HTTPException, Request
from fastapi.responses import StreamingResponse
from pydantic import BaseModel, ConfigDict, Field

from server.deps import CtxDep, Viewer
from server.schemas import Message

router = APIRouter(prefix="/api", tags=["live"])
BOUNDARY = "tmeyeframe"


class SessionDescription(BaseModel):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"sdp": "v=0\r\no=- 4611731400430051336 2 IN IP4 127.0.0.1\r\ns=-\r\nt=0 0\r\n…", "type": "offer"}]})

    sdp: str = Field(min_length=10, max_length=100_000)
    type: Literal["offer", "answer"]


class WebRTCConfig(BaseModel):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"ice_servers": []}, {"ice_servers": ["stun:stun.example.org:3478"]}]})

    ice_servers: list[str]


@router.get("/webrtc/config", response_model=WebRTCConfig, summary="ICE servers for the browser (none by default)")
def webrtc_config(ctx: CtxDep, _p: Viewer) -> WebRTCConfig:
    return WebRTCConfig(ice_servers=ctx.settings.ice_servers)


@router.post("/webrtc/offer", response_model=SessionDescription, responses={422: {"model": Message}},
             summary="Offer receive-only video transceivers (1st: left camera, 2nd: right); get the answer")
async def webrtc_offer(body: SessionDescription, ctx: CtxDep, _p: Viewer) -> SessionDescription:
    if body.type != "offer":
        raise HTTPException(422, "type must be 'offer'")
    try:
        answer = await asyncio.wait_for(ctx.viewers.answer(body.sdp, body.type), 15.0)
    except (ValueError, TypeError) as exc:
        raise HTTPException(422, f"unusable offer: {str(exc).splitlines()[0] if str(exc) else type(exc).__name__}"
                            ) from None
    except TimeoutError:
        raise HTTPException(503, "ICE gathering did not finish in time") from None
    return SessionDescription(sdp=answer.sdp, type="answer")


async def _mjpeg(request: Request, ctx: CtxDep, camera: str) -> AsyncIterator[bytes]:
    loop = asyncio.get_running_loop()
    ready = asyncio.Event()
    hub = ctx.media.jpegs[camera]
    sub = hub.subscribe(maxsize=2, name=f"mjpeg-{camera}", notify=lambda: loop.call_soon_threadsafe(ready.set))
    try:
        while not sub.closed and not ctx.stopping.is_set():
            try:
                await asyncio.wait_for(ready.wait(), 1.0)
            except TimeoutError:
                if await request.is_disconnected():
                    return
                continue
            ready.clear()
            for jf in sub.drain()[-1:]:
                yield (f"--{BOUNDARY}\r\nContent-Type: image/jpeg\r\nContent-Length: {len(jf.data)}\r\n"
                       f"X-Frame-Index: {jf.frame_no}\r\nX-Captured-At: {jf.captured_at:.6f}\r\n\r\n").encode() \
                    + jf.data + b"\r\n"
    finally:
        hub.unsubscribe(sub)


@router.get("/live/{camera}.mjpeg", response_class=StreamingResponse, summary="MJPEG fallback of one camera",
            responses={200: {"content": {f"multipart/x-mixed-replace; boundary={BOUNDARY}": {}}}})
async def mjpeg(camera: Literal["left", "right"], request: Request, ctx: CtxDep, _p: Viewer) -> StreamingResponse:
    return StreamingResponse(_mjpeg(request, ctx, camera), media_type=f"multipart/x-mixed-replace; boundary={BOUNDARY}",
                             headers={"Cache-Control": "no-store"})
