"""The media thread: frames from the runtime -> one H.264 encoder per camera -> packets for every viewer
(and the recorder); JPEGs for MJPEG clients, encoded once per frame whatever their number.

It subscribes to the runtime with a short queue (drop-oldest, `queue` frames): encoding never slows the tracker, and a
slow encoder skips frames rather than lagging. Cameras are encoded only while someone consumes them
(`demand`): a viewer joining asks for a keyframe (`request_keyframe`)."""

from __future__ import annotations

import logging
import threading
import time
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from tmeye.media.encoder import EncodedFrame, H264Encoder, pts_of, stamp
from tmeye.runtime.events import FrameEvent
from tmeye.runtime.publish import Hub
from tmeye.runtime.threads import lower_priority
from tmeye.runtime.worker import Runtime

log = logging.getLogger("tmeye.media")
CAMERAS = ("left", "right")


@dataclass(frozen=True)
class MediaConfig:
    """bitrate: H.264 bits per second per camera; gop: frames between keyframes; stamp_frames: draw the
    frame index in the top-left corner of the video (never the tracker's input); mjpeg_fps / mjpeg_quality:
    the MJPEG fallback's rate (frames per second) and JPEG quality (1-100); queue: frames waiting for the
    encoders before the oldest is dropped (a dropped frame is neither shown nor recorded); nice: how much
    nicer than the tracker's worker the encoding thread and libx264's threads run (0: the same)."""

    bitrate: int = 1_500_000
    gop: int = 30
    stamp_frames: bool = False
    mjpeg_fps: float = 15.0
    mjpeg_quality: int = 80
    queue: int = 2
    nice: int = 0


@dataclass(frozen=True)
class JpegFrame:
    camera: str
    data: bytes
    frame_no: int
    captured_at: float


class MediaPipeline:
    def __init__(self, runtime: Runtime, config: MediaConfig | None = None):
        self.runtime, self.config = runtime, config or MediaConfig()
        self.packets: dict[str, Hub[EncodedFrame]] = {c: Hub() for c in CAMERAS}
        self.jpegs: dict[str, Hub[JpegFrame]] = {c: Hub() for c in CAMERAS}
        self.recorders = 0  # consumers other than viewers that need packets (the recorder)
        self._encoders: dict[str, H264Encoder] = {}
        self._key = {c: True for c in CAMERAS}
        self._last_jpeg = {c: 0.0 for c in CAMERAS}
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.encoded = self.encode_errors = 0
        self.encode_ms: list[float] = []

    def start(self) -> None:
        self._thread = threading.Thread(target=self._run, name="tmeye-media", daemon=True)
        self._thread.start()

    def stop(self, timeout: float = 2.0) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout)
        for enc in self._encoders.values():
            enc.close()
        for hub in self.packets.values():
            hub.close()
        for jhub in self.jpegs.values():
            jhub.close()

    def request_keyframe(self, camera: str) -> None:
        self._key[camera] = True

    def demand(self, camera: str) -> bool:
        return self.packets[camera].subscribers > 0 or self.recorders > 0

    def _run(self) -> None:
        lower_priority(self.config.nice)  # before the encoders start their threads, which inherit it
        sub = self.runtime.hub.subscribe(maxsize=self.config.queue, name="media")
        try:
            while not self._stop.is_set():
                ev = sub.get(timeout=0.2)
                if ev is None:
                    if sub.closed:
                        return
                    continue
                try:
                    self._frame(ev)
                except Exception:
                    self.encode_errors += 1
                    log.exception("encoding frame %d failed", ev.frame_no)
        finally:
            self.runtime.hub.unsubscribe(sub)

    def _images(self, ev: FrameEvent) -> dict[str, NDArray[np.uint8]]:
        f = ev.frame
        imgs = {"left": getattr(f, "left_colour", None), "right": getattr(f, "right_colour", None)}
        out = {c: (img if img is not None else getattr(f, c)) for c, img in imgs.items()}
        if self.config.stamp_frames:
            out = {c: stamp(img, ev.frame_no) for c, img in out.items()}
        return out

    def _frame(self, ev: FrameEvent) -> None:
        want = [c for c in CAMERAS if self.demand(c)]
        jpeg = [c for c in CAMERAS if self.jpegs[c].subscribers > 0
                and ev.captured_at - self._last_jpeg[c] >= 1.0 / self.config.mjpeg_fps - 1e-3]
        if not want and not jpeg:
            return
        imgs = self._images(ev)
        for c in want:
            self._encode(c, imgs[c], ev)
        for c in jpeg:
            ok, buf = cv2.imencode(".jpg", imgs[c], [cv2.IMWRITE_JPEG_QUALITY, self.config.mjpeg_quality])
            if ok:
                self._last_jpeg[c] = ev.captured_at
                self.jpegs[c].publish(JpegFrame(c, buf.tobytes(), ev.frame_no, ev.captured_at))

    def _encode(self, camera: str, img: NDArray[np.uint8], ev: FrameEvent) -> None:
        enc = self._encoders.get(camera)
        h, w = img.shape[:2]
        if enc is None or (enc.width, enc.height) != (w, h):
            enc = self._encoders[camera] = H264Encoder(w, h, self.runtime.comp.fps if self.runtime.comp else 30.0,
                                                       self.config.bitrate, self.config.gop)
            self._key[camera] = True
        key, self._key[camera] = self._key[camera], False
        t0 = time.perf_counter()
        out = enc.encode(img, pts_of(ev.captured_at), key)
        self.encode_ms.append((time.perf_counter() - t0) * 1e3)
        del self.encode_ms[:-600]
        self.encoded += 1
        for data, pts, is_key in out:
            self.packets[camera].publish(EncodedFrame(camera, data, pts, is_key, ev.frame_no, ev.captured_at))

