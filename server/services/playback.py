"""Frame-exact playback: the JPEG of the last frame of a camera captured at or before a time, decoded on the
server from the nearest keyframe before it. Decoded keyframe groups are cached (stepping through a group
decodes it once), and so are the JPEGs. Call from a worker thread (`asyncio.to_thread`), never the loop."""

from __future__ import annotations

import bisect
import threading
from collections import OrderedDict
from collections.abc import Callable, Iterator
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
    """Decoded keyframe groups (LRU of `groups`), JPEGs (LRU of `jpegs`) and the open decoders of the last few
    segments (LRU of `decoders`): a frame later in the group the decoder is in is reached by decoding forward
    from where it stopped (stepping or playing forward decodes one frame per step), any other by a seek to its
    keyframe in the already open file."""

    def __init__(self, data_dir: Path, groups: int = 4, jpegs: int = 512, quality: int = 90, decoders: int = 4):
        self.data_dir, self.quality = data_dir, quality
        self._groups: OrderedDict[tuple[int, int], dict[int, av.VideoFrame]] = OrderedDict()
        self._jpegs: OrderedDict[tuple[int, int], bytes] = OrderedDict()
        self._decoders: OrderedDict[int, SegmentDecoder] = OrderedDict()
        self._max_groups, self._max_jpegs, self._max_decoders = groups, jpegs, decoders
        self._lock = threading.Lock()
        self.decoded_groups = 0  # keyframe groups a decoder was sent to (a seek or a segment opened)

    def jpeg(self, ref: FrameRef) -> FrameJpeg:
        key = (ref.segment_id, ref.offset)
        with self._lock:
            data = self._jpegs.get(key)
            if data is None:
                frame = self._frame(ref)
                if frame is None:
                    raise NotFound(f"frame at {ref.offset / CLOCK_HZ:.3f} s of segment {ref.segment_id} "
                                   "does not decode")
                data = encode_jpeg(frame, self.quality)
                self._jpegs[key] = data
                while len(self._jpegs) > self._max_jpegs:
                    self._jpegs.popitem(last=False)
            self._jpegs.move_to_end(key)
        return FrameJpeg(data, ref.frame_no, ref.captured_at, ref.segment_id, ref.offset / CLOCK_HZ)

    def _frame(self, ref: FrameRef) -> av.VideoFrame | None:
        gkey = (ref.segment_id, ref.key_offset)
        group = self._groups.get(gkey)
        if group is None or ref.offset not in group:
            dec = self._decoders.get(ref.segment_id)
            if dec is None:
                dec = self._decoders[ref.segment_id] = SegmentDecoder(self.data_dir / ref.path)
                while len(self._decoders) > self._max_decoders:
                    self._decoders.popitem(last=False)[1].close()
            self._decoders.move_to_end(ref.segment_id)
            self.decoded_groups += dec.decode_to(ref.key_offset, ref.offset,
                                                 lambda k, pts, f: self._store(ref.segment_id, k, pts, f))
            group = self._groups.get(gkey)
        if group is None:
            return None
        self._groups.move_to_end(gkey)
        return group.get(ref.offset)

    def _store(self, segment_id: int, key_offset: int, pts: int, frame: av.VideoFrame) -> None:
        gkey = (segment_id, key_offset)
        group = self._groups.get(gkey)
        if group is None:
            group = self._groups[gkey] = {}
            while len(self._groups) > self._max_groups:
                self._groups.popitem(last=False)
        group[pts] = frame


def encode_jpeg(frame: av.VideoFrame, quality: int) -> bytes:
    """JPEG of a decoded frame: a 4:2:0 frame is turned into BGR by OpenCV (cheaper than libswscale's bgr24)."""
    if frame.format.name == "yuv420p" and frame.width % 2 == 0 and frame.height % 2 == 0:
        bgr = cv2.cvtColor(frame.to_ndarray(format="yuv420p"), cv2.COLOR_YUV2BGR_I420)
    else:
        bgr = frame.to_ndarray(format="bgr24")
    ok, buf = cv2.imencode(".jpg", bgr, [cv2.IMWRITE_JPEG_QUALITY, quality])
    return buf.tobytes() if ok else b""


class SegmentDecoder:
    """One segment's open file and decoder. `decode_to(key, offset, store)` decodes the keyframe group that
    starts at `key` (90 kHz ticks in the segment) up to `offset`, handing each frame to store(key, pts, frame):
    forward from where it stopped when it is in that group before `offset`, else after a seek to `key`."""

    def __init__(self, path: Path):
        self.container: av.container.InputContainer | None = av.open(str(path))
        self.stream = self.container.streams.video[0]
        self.stream.codec_context.thread_type = "NONE"  # one thread: each packet's frame comes out at once (measured
        # faster here than slice or frame threads for decoding up to one frame of a group)
        self._it: Iterator[av.VideoFrame] | None = None
        self.group: int | None = None  # the keyframe group of the last frame decoded
        self.pos = -1  # the last frame decoded (ticks)

    def _frames(self) -> Iterator[av.VideoFrame]:
        assert self.container is not None
        try:
            for pkt in self.container.demux(self.stream):
                yield from pkt.decode()
        except av.error.InvalidDataError:
            return  # the cut tail of a segment

    def decode_to(self, key: int, offset: int, store: Callable[[int, int, av.VideoFrame], None]) -> int:
        """Returns 1 if a seek was needed, else 0."""
        if self.container is None:
            return 0
        sought = 0
        if self._it is None or self.group != key or self.pos >= offset:
            self.container.seek(key, stream=self.stream, backward=True, any_frame=False)
            self._it, self.group, self.pos, sought = self._frames(), None, -1, 1
        while self.pos < offset:
            frame = next(self._it, None)
            if frame is None:
                self._it = None  # the segment ended
                break
            if frame.pts is None:
                continue
            pts = int(frame.pts)
            if frame.key_frame:
                self.group = pts
            if self.group is None or pts < key:
                continue
            self.pos = pts
            store(self.group, pts, frame)
            if self.group != key:  # the next group began (kept for a request there): `offset` is not in this one
                break
        return sought

    def close(self) -> None:
        if self.container is not None:
            self.container.close()
            self.container = None
