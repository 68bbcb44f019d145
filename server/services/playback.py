"""Frame-exact playback: the JPEG of the last frame of a camera captured at or before a time, decoded on the
server from the nearest keyframe before it. Decoded keyframe groups are cached (stepping through a group
decodes it once), and so are the JPEGs. Call from a worker thread (`asyncio.to_thread`), never the loop."""

from __future__ import annotations

import bisect
import threading
from collections import OrderedDict
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import av
import cv2
from sqlalchemy import select
from sqlalchemy.orm import Session

from server.db.models import RecordedFrame, Segment
from server.services.errors import NotFound
from server.services.segments import segment_at
from tmeye.media.encoder import CLOCK_HZ

MAX_GAP_S = 1.0  # a time further than this after a segment's last frame is not recorded
# "at or before t" within one 90 kHz tick: a capture time given with 6 decimals (the telemetry's) finds its frame
TOLERANCE_S = 1.5 / CLOCK_HZ


@dataclass(frozen=True)
class FrameJpeg:
    data: bytes
    frame_no: int
    captured_at: float
    segment_id: int
    t_in_segment: float


@dataclass(frozen=True)
class FrameRef:
    """Which frame of which segment: its offset (90 kHz ticks) and its keyframe group's first offset."""

    segment_id: int
    path: str
    offset: int
    key_offset: int
    frame_no: int
    captured_at: float


def locate(db: Session, camera: str, t: float) -> FrameRef:
    """The last frame of `camera` captured at or before t (Unix s); NotFound where nothing was recorded."""
    seg = segment_at(db, camera, t + TOLERANCE_S)
    if seg is None or seg.end is None or not seg.frame_offsets or t > seg.end + MAX_GAP_S:
        raise NotFound(f"no recording of the {camera} camera at t={t:.3f}")
    return frame_ref(db, seg, round((t + TOLERANCE_S) * CLOCK_HZ) - seg.start_pts)


def frame_ref(db: Session, seg: Segment, ticks: int) -> FrameRef:
    offs: list[int] = seg.frame_offsets
    i = max(bisect.bisect_right(offs, ticks) - 1, 0)
    keys = [round(k * CLOCK_HZ) for k in seg.keyframes] or [0]
    k = max(bisect.bisect_right(keys, offs[i]) - 1, 0)
    pts = seg.start_pts + offs[i]
    captured = db.scalar(select(RecordedFrame.captured_at).where(RecordedFrame.pts == pts))
    return FrameRef(seg.id, seg.path, offs[i], keys[k], int(seg.frame_nos[i]) if i < len(seg.frame_nos) else -1,
                    captured if captured is not None else pts / CLOCK_HZ)


class FrameCache:
    """Decoded keyframe groups (LRU of `groups`) and JPEGs (LRU of `jpegs`) of recorded segments."""

    def __init__(self, data_dir: Path, groups: int = 4, jpegs: int = 512, quality: int = 90):
        self.data_dir, self.quality = data_dir, quality
        self._groups: OrderedDict[tuple[int, int], GroupDecoder] = OrderedDict()
        self._jpegs: OrderedDict[tuple[int, int], bytes] = OrderedDict()
        self._max_groups, self._max_jpegs = groups, jpegs
        self._lock = threading.Lock()
        self.decoded_groups = 0

    def jpeg(self, ref: FrameRef) -> FrameJpeg:
        key = (ref.segment_id, ref.offset)
        with self._lock:
            data = self._jpegs.get(key)
            if data is None:
                frame = self._group(ref).get(ref.offset)
                if frame is None:
                    raise NotFound(f"frame at {ref.offset / CLOCK_HZ:.3f} s of segment {ref.segment_id} "
                                   "does not decode")
                ok, buf = cv2.imencode(".jpg", frame.to_ndarray(format="bgr24"), [cv2.IMWRITE_JPEG_QUALITY,
                                                                                 self.quality])
                data = buf.tobytes() if ok else b""
                self._jpegs[key] = data
                while len(self._jpegs) > self._max_jpegs:
                    self._jpegs.popitem(last=False)
            self._jpegs.move_to_end(key)
        return FrameJpeg(data, ref.frame_no, ref.captured_at, ref.segment_id, ref.offset / CLOCK_HZ)

    def _group(self, ref: FrameRef) -> dict[int, av.VideoFrame]:
        key = (ref.segment_id, ref.key_offset)
        group = self._groups.get(key)
        if group is None:
            group = self._groups[key] = GroupDecoder(self.data_dir / ref.path, ref.key_offset)
            self.decoded_groups += 1
            while len(self._groups) > self._max_groups:
                self._groups.popitem(last=False)[1].close()
        self._groups.move_to_end(key)
        return group.upto(ref.offset)


class GroupDecoder:
    """One keyframe group of a segment, decoded on demand from its keyframe: a later frame of the same group
    continues where the decoder stopped (stepping forward decodes one frame per step)."""

    def __init__(self, path: Path, key_offset: int):
        self.key_offset = key_offset
        self.frames: dict[int, av.VideoFrame] = {}
        self.container: av.container.InputContainer | None = av.open(str(path))
        st = self.container.streams.video[0]
        st.codec_context.thread_type = "NONE"  # one thread: each packet's frame comes out at once (measured faster
        # here than slice or frame threads for decoding up to one frame of a group)
        self.container.seek(key_offset, stream=st, backward=True, any_frame=False)
        self._it = self._frames(st)

    def _frames(self, st: av.video.stream.VideoStream) -> Iterator[av.VideoFrame]:
        assert self.container is not None
        try:
            for pkt in self.container.demux(st):
                yield from pkt.decode()
        except av.error.InvalidDataError:
            return  # the cut tail of a segment

    def upto(self, offset: int) -> dict[int, av.VideoFrame]:
        while offset not in self.frames and self.container is not None:
            frame = next(self._it, None)
            if frame is None or (frame.key_frame and frame.pts is not None and frame.pts > self.key_offset):
                self.close()  # the group ended
            elif frame.pts is not None and frame.pts >= self.key_offset:
                self.frames[int(frame.pts)] = frame
        return self.frames

    def close(self) -> None:
        if self.container is not None:
            self.container.close()
            self.container = None
