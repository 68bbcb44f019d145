"""H.264 encoding of one camera with PyAV's libx264, and the frame-index stamp of measurement mode.

Timestamps: the presentation time of a frame is its capture time on a 90 kHz clock,
pts = round(captured_at · 90000) (captured_at in Unix seconds); RTP carries it mod 2³², so a viewer
can match each decoded frame to the telemetry of the same capture.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from fractions import Fraction

import av
import numpy as np
from av.video.frame import PictureType
from numpy.typing import NDArray

CLOCK_HZ = 90000
STAMP_BITS, STAMP_CELL = 16, 8


def pts_of(captured_at: float) -> int:
    """The 90 kHz presentation time of a capture at Unix time `captured_at` (s)."""
    return int(round(captured_at * CLOCK_HZ))


def stamp(img: NDArray[np.uint8], index: int) -> NDArray[np.uint8]:
    """A copy of img with `index mod 65536` drawn in its top-left corner: one row of 16 cells of 8x8 px from
    x = 0, y = 0, most significant bit first, 255 for 1 and 0 for 0 (every channel of a colour image)."""
    out = img.copy()
    v = index % (1 << STAMP_BITS)
    for k in range(STAMP_BITS):
        bit = (v >> (STAMP_BITS - 1 - k)) & 1
        out[0:STAMP_CELL, k * STAMP_CELL:(k + 1) * STAMP_CELL] = 255 if bit else 0
    return out


def read_stamp(img: NDArray[np.uint8]) -> int:
    """The index stamped by `stamp`, read from the centre of each cell (grey or colour; survives lossy video)."""
    grey = img if img.ndim == 2 else img.mean(axis=2)
    c = STAMP_CELL // 2
    bits = [int(grey[c - 1:c + 1, k * STAMP_CELL + c - 1:k * STAMP_CELL + c + 1].mean() > 127)
            for k in range(STAMP_BITS)]
    return int("".join(map(str, bits)), 2)


@dataclass(frozen=True)
class EncodedFrame:
    """One camera's encoded frame: Annex B H.264 (SPS/PPS in-band before keyframes), pts on the 90 kHz
    capture clock, the runtime's frame number and capture time (Unix s)."""

    camera: str
    data: bytes
    pts: int
    keyframe: bool
    frame_no: int
    captured_at: float


class H264Encoder:
    """libx264, baseline profile, zerolatency (one packet out per frame in), a keyframe every `gop`
    frames or on request. Input: grey (H, W) or BGR (H, W, 3) uint8."""

    def __init__(self, width: int, height: int, fps: float, bitrate: int = 1_500_000, gop: int = 45):
        ctx = av.CodecContext.create("libx264", "w")
        ctx.width, ctx.height = width, height
        ctx.pix_fmt = "yuv420p"
        ctx.time_base = Fraction(1, CLOCK_HZ)
        ctx.framerate = Fraction(round(fps * 1000), 1000)
        ctx.bit_rate = bitrate
        ctx.gop_size = gop
        ctx.options = {"preset": "ultrafast", "tune": "zerolatency", "profile": "baseline",
                       "x264-params": f"keyint={gop}:min-keyint={gop}:scenecut=0:repeat-headers=1"}
        self.ctx = ctx
        self.width, self.height = width, height
        self._last_pts = -1

    def encode(self, img: NDArray[np.uint8], pts: int, keyframe: bool = False) -> list[tuple[bytes, int, bool]]:
        """[(data, pts, is keyframe)] for one image; pts must increase (a repeat is nudged by one tick)."""
        pts = max(pts, self._last_pts + 1)
        self._last_pts = pts
        fmt = "gray" if img.ndim == 2 else "bgr24"
        frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(img), format=fmt).reformat(format="yuv420p")
        frame.pts = pts
        frame.time_base = Fraction(1, CLOCK_HZ)
        if keyframe:
            frame.pict_type = PictureType.I
        return [(bytes(p), int(p.pts if p.pts is not None else pts), bool(p.is_keyframe))
                for p in self.ctx.encode(frame)]

    def close(self) -> None:
        with contextlib.suppress(av.error.FFmpegError):
            self.ctx.encode(None)  # flush
