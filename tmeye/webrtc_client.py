"""A WebRTC viewer in Python (aiortc) for tests and `tmeye bench --webrtc`: offers two receive-only video
transceivers to a TMEye server, decodes both cameras, and for every frame records its stamp (the frame
index drawn by `--stamp-frames`), RTP timestamp and the time it was decoded."""

from __future__ import annotations

import asyncio
import time
from dataclasses import dataclass, field
from typing import Any

from tmeye.media.encoder import read_stamp


@dataclass
class Received:
    camera: str
    frames: list[tuple[float, int, int]] = field(default_factory=list)  # (decoded at Unix s, rtp ts, stamp)
    last_bgr: Any = None  # the last decoded image, BGR (H, W, 3), when asked for (keep_last)


async def _consume(track: Any, rec: Received, until: float, read_stamps: bool, keep_last: bool) -> None:
    while time.monotonic() < until:
        try:
            frame = await asyncio.wait_for(track.recv(), max(until - time.monotonic(), 0.01))
        except (TimeoutError, Exception):
            return
        now = time.time()
        stamp = read_stamp(frame.to_ndarray(format="gray")) if read_stamps else -1
        rec.frames.append((now, int(frame.pts or 0), stamp))
        if keep_last:
            rec.last_bgr = frame.to_ndarray(format="bgr24")


async def view(base_url: str, token: str, seconds: float, read_stamps: bool = True,
               keep_last: bool = False) -> list[Received]:
    """Watch both cameras for `seconds`; returns what each camera delivered (and its last image in colour,
    with keep_last)."""
    import httpx
    from aiortc import RTCConfiguration, RTCPeerConnection, RTCSessionDescription

    pc = RTCPeerConnection(RTCConfiguration(iceServers=[]))
    pc.addTransceiver("video", direction="recvonly")
    pc.addTransceiver("video", direction="recvonly")
    recs = [Received("left"), Received("right")]
    tasks: list[asyncio.Task[None]] = []
    until = time.monotonic() + seconds

    @pc.on("track")
    def on_track(track: Any) -> None:
        idx = len(tasks)
        tasks.append(asyncio.ensure_future(_consume(track, recs[min(idx, 1)], until, read_stamps, keep_last)))

    await pc.setLocalDescription(await pc.createOffer())
    async with httpx.AsyncClient(base_url=base_url, headers={"Authorization": f"Bearer {token}"}, timeout=30) as c:
        r = await c.post("/api/webrtc/offer", json={"sdp": pc.localDescription.sdp, "type": "offer"})
        r.raise_for_status()
        await pc.setRemoteDescription(RTCSessionDescription(**r.json()))
    await asyncio.sleep(max(until - time.monotonic(), 0))
    await asyncio.gather(*tasks, return_exceptions=True)
    await pc.close()
    return recs


async def telemetry_messages(base_url: str, token: str, seconds: float) -> list[tuple[int, float]]:
    """(frame number, captured_at Unix s) of every /ws/telemetry message over `seconds`."""
    import json

    import websockets

    out: list[tuple[int, float]] = []
    url = base_url.replace("http://", "ws://") + "/ws/telemetry"
    async with websockets.connect(url, additional_headers={"Authorization": f"Bearer {token}"},
                                  max_queue=None) as ws:
        end = time.monotonic() + seconds
        while (left := end - time.monotonic()) > 0:
            try:
                m = json.loads(await asyncio.wait_for(ws.recv(), left))
            except TimeoutError:
                break
            out.append((int(m["frame"]), float(m["captured_at"])))
    return out


async def telemetry_times(base_url: str, token: str, seconds: float) -> dict[int, float]:
    """frame number mod 65536 -> captured_at (Unix s), from /ws/telemetry over `seconds`."""
    return {f % 65536: t for f, t in await telemetry_messages(base_url, token, seconds)}


def latency_ms(rec: Received, captured: dict[int, float]) -> list[float]:
    """Capture to decoded frame (ms) of every frame whose stamp has telemetry."""
    return sorted((t - captured[s]) * 1e3 for t, _, s in rec.frames if s in captured)


def _q(v: list[float], p: float) -> float | None:
    return round(v[min(len(v) - 1, int(p * (len(v) - 1)))], 1) if v else None


async def measure(base_url: str, token: str, clients: int, seconds: float) -> dict[str, Any]:
    """`clients` viewers at once plus a telemetry listener; per camera the decoded rate (fps, the slowest
    client) and the capture-to-decoded latency percentiles (ms) over all clients."""
    tel = asyncio.create_task(telemetry_times(base_url, token, seconds + 2.0))
    views = await asyncio.gather(*(view(base_url, token, seconds) for _ in range(clients)))
    captured = await tel
    out: dict[str, Any] = {"clients": clients, "seconds": seconds}
    for k, cam in enumerate(("left", "right")):
        recs = [v[k] for v in views]
        rates = []
        for r in recs:
            fr = r.frames[len(r.frames) // 10:]  # after the first tenth (connection set-up)
            rates.append((len(fr) - 1) / (fr[-1][0] - fr[0][0]) if len(fr) > 2 else 0.0)
        lat = sorted(v for r in recs for v in latency_ms(r, captured))
        out[cam] = {"fps_min": round(min(rates), 2), "latency_ms": {"n": len(lat), "p50": _q(lat, 0.5),
                                                                   "p95": _q(lat, 0.95), "p99": _q(lat, 0.99)},
                    "stamps_increasing": all(all(b[2] > a[2] or b[2] < 100 < a[2] for a, b in
                                                 zip(r.frames, r.frames[1:], strict=False)) for r in recs)}
    return out
