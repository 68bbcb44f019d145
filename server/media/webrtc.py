"""WebRTC with aiortc, encode-once: each viewer's video track returns the shared encoder's `av.Packet`s,
which aiortc's sender packetises without encoding again (its H.264 `pack`).

RTP timestamps: aiortc adds a random 32-bit origin to each stream's timestamps. TMEye's viewers match
each frame to its telemetry by the RTP timestamp, so the origin is made 0 for the RTP loop (only there:
SSRCs stay random); a frame's RTP timestamp is then round(captured_at · 90000) mod 2³², which a client
computes from the telemetry's `captured_at`.
"""

from __future__ import annotations

import asyncio
import logging
import sys
from fractions import Fraction
from typing import Any

import aiortc.rtcrtpsender as _sender
import av
from aiortc import RTCConfiguration, RTCIceServer, RTCPeerConnection, RTCRtpSender, RTCSessionDescription
from aiortc.mediastreams import MediaStreamError, MediaStreamTrack

from tmeye.media.encoder import CLOCK_HZ, EncodedFrame
from tmeye.media.pipeline import CAMERAS, MediaPipeline

log = logging.getLogger("tmeye.webrtc")
_random32 = _sender.random32  # type: ignore[attr-defined]


def _origin_zero_in_rtp_loop() -> int:
    """random32 for aiortc's sender, except the RTP loop's timestamp origin, which is 0."""
    caller = sys._getframe(1).f_code.co_name
    return 0 if caller == "_run_rtp" else _random32()


_sender.random32 = _origin_zero_in_rtp_loop  # type: ignore[attr-defined]


class PacketTrack(MediaStreamTrack):
    """A video track of one camera: the media pipeline's packets, starting at a keyframe."""

    kind = "video"

    def __init__(self, media: MediaPipeline, camera: str, queue: int = 8):
        super().__init__()
        self.media, self.camera = media, camera
        loop = asyncio.get_running_loop()
        self._ready = asyncio.Event()
        self._sub = media.packets[camera].subscribe(maxsize=queue, name=f"webrtc-{camera}",
                                                    notify=lambda: loop.call_soon_threadsafe(self._ready.set))
        self._pending: list[EncodedFrame] = []
        self._started = False
        media.request_keyframe(camera)

    async def recv(self) -> av.Packet:
        while True:
            if self.readyState != "live":
                raise MediaStreamError
            if not self._pending:
                self._ready.clear()
                self._pending = self._sub.drain()
                if not self._pending:
                    if self._sub.closed:
                        self.stop()
                        raise MediaStreamError
                    await self._ready.wait()
                    continue
            ef = self._pending.pop(0)
            if self._sub.dropped and not ef.keyframe and self._lost():
                continue
            if not self._started and not ef.keyframe:
                continue  # a viewer starts at a keyframe (requested when it joined)
            self._started = True
            pkt = av.Packet(ef.data)
            pkt.pts = pkt.dts = ef.pts
            pkt.time_base = Fraction(1, CLOCK_HZ)
            return pkt

    def _lost(self) -> bool:
        """Packets were dropped for this viewer (it fell behind): wait for a fresh keyframe."""
        self._sub.dropped = 0
        self._started = False
        self.media.request_keyframe(self.camera)
        return True

    def stop(self) -> None:
        super().stop()
        self.media.packets[self.camera].unsubscribe(self._sub)


class Viewers:
    """The peer connections of the WebRTC viewers; closed at shutdown."""

    def __init__(self, media: MediaPipeline, ice_servers: list[str]):
        self.media = media
        self.ice = [RTCIceServer(urls=u) for u in ice_servers]
        self.pcs: set[RTCPeerConnection] = set()

    async def answer(self, sdp: str, kind: str) -> RTCSessionDescription:
        """Answer an offer of receive-only video transceivers: the first gets the left camera, the second
        the right (H.264 only). Non-trickle: the answer holds the gathered candidates."""
        offer = RTCSessionDescription(sdp=sdp, type=kind)
        wanted = sum(1 for line in sdp.splitlines() if line.startswith("m=video"))
        if wanted < 1:
            raise ValueError("the offer has no video transceiver")
        pc = RTCPeerConnection(RTCConfiguration(iceServers=self.ice))
        self.pcs.add(pc)

        @pc.on("connectionstatechange")
        async def on_state() -> None:
            if pc.connectionState in ("failed", "closed"):
                await self._close(pc)
        try:
            h264 = [c for c in RTCRtpSender.getCapabilities("video").codecs if c.mimeType == "video/H264"]
            for camera in CAMERAS[:wanted]:
                tr = pc.addTransceiver(PacketTrack(self.media, camera), direction="sendonly")
                tr.setCodecPreferences(h264)
            await pc.setRemoteDescription(offer)
            await pc.setLocalDescription(await pc.createAnswer())
        except Exception:
            await self._close(pc)
            raise
        return pc.localDescription

    async def _close(self, pc: RTCPeerConnection) -> None:
        self.pcs.discard(pc)
        for sender in pc.getSenders():
            if sender.track is not None:
                sender.track.stop()
        await pc.close()

    async def close(self) -> None:
        await asyncio.gather(*(self._close(pc) for pc in list(self.pcs)), return_exceptions=True)

    def stats(self) -> dict[str, Any]:
        return {"viewers": len(self.pcs)}
