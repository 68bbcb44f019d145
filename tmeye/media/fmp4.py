"""Fragmented MP4 segments of the encoder's H.264 packets, written without encoding again.

A segment file is `ftyp moov (moof mdat)* [mfra]` (movflags frag_keyframe+empty_moov+default_base_moof): one
fragment per keyframe group, each written when the next keyframe comes. Packet times in the file are the 90 kHz
capture clock minus the segment's first pts, so a frame's time in the segment is its pts / 90000 s and its capture
time is (start_pts + pts) / 90000 s. A file cut by a crash keeps every complete fragment: `complete_length`
finds where the last one ends, and `truncate_to_fragments` cuts the rest.
"""

from __future__ import annotations

import os
import re
import struct
from collections.abc import Iterator
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path

import av

from tmeye.media.encoder import CLOCK_HZ, EncodedFrame

MOVFLAGS = "frag_keyframe+empty_moov+default_base_moof"
_START = re.compile(b"\x00\x00\x01")


def split_nals(data: bytes) -> list[bytes]:
    """The NAL units of an Annex B byte stream (start codes of 3 or 4 bytes removed)."""
    starts = [m.end() for m in _START.finditer(data)]
    out = []
    for i, s in enumerate(starts):
        e = starts[i + 1] - 3 if i + 1 < len(starts) else len(data)
        out.append(data[s:e].rstrip(b"\x00") if i + 1 < len(starts) else data[s:e])
    return out


def parameter_sets(data: bytes) -> bytes:
    """The SPS and PPS (NAL types 7, 8) of a keyframe as Annex B bytes: the MP4 muxer's extradata."""
    sets = [n for n in split_nals(data) if n and n[0] & 0x1F in (7, 8)]
    if not sets:
        raise ValueError("keyframe without SPS/PPS (the encoder must repeat its headers)")
    return b"".join(b"\x00\x00\x00\x01" + n for n in sets)


def frame_size(keyframe: bytes) -> tuple[int, int]:
    """(width, height) of a keyframe, by decoding it once."""
    ctx = av.CodecContext.create("h264", "r")
    frames = ctx.decode(av.Packet(keyframe)) + ctx.decode(None)
    if not frames:
        raise ValueError("the keyframe does not decode")
    return frames[0].width, frames[0].height


@dataclass(frozen=True)
class Box:
    kind: str
    offset: int
    size: int

    @property
    def end(self) -> int:
        return self.offset + self.size


def boxes(path: Path) -> Iterator[Box]:
    """The complete top-level boxes of an MP4 file, in order; stops at the first cut or malformed one."""
    total = path.stat().st_size
    with path.open("rb") as f:
        off = 0
        while off + 8 <= total:
            f.seek(off)
            head = f.read(16)
            size, kind = struct.unpack(">I4s", head[:8])
            if size == 1 and len(head) >= 16:
                size = struct.unpack(">Q", head[8:16])[0]
            elif size == 0:
                size = total - off
            if size < 8 or off + size > total:
                return
            yield Box(kind.decode("latin-1"), off, size)
            off += size


@dataclass(frozen=True)
class Layout:
    """init_bytes: length of ftyp+moov; fragments: (offset, length) of each moof+mdat pair; length: where the
    last complete fragment ends (0: not even the header is complete)."""

    init_bytes: int
    fragments: list[tuple[int, int]]
    length: int


def layout(path: Path) -> Layout:
    init, frags, moof = 0, [], None
    for b in boxes(path):
        if b.kind == "moov":
            init = b.end
        elif b.kind == "moof" and init:
            moof = b
        elif b.kind == "mdat" and moof is not None:
            frags.append((moof.offset, b.end - moof.offset))
            moof = None
    length = frags[-1][0] + frags[-1][1] if frags else init
    return Layout(init, frags, length)


def complete_length(path: Path) -> int:
    return layout(path).length


def truncate_to_fragments(path: Path) -> int:
    """Cut `path` after its last complete fragment; returns the new length (0: nothing usable)."""
    n = complete_length(path)
    if n < path.stat().st_size:
        os.truncate(path, n)
    return n


@dataclass
class DecodedIndex:
    """What a segment file holds: frame pts (90 kHz ticks from the segment start) and the keyframes'."""

    pts: list[int] = field(default_factory=list)
    keyframes: list[int] = field(default_factory=list)


def index_file(path: Path) -> DecodedIndex:
    """Every frame's pts by demuxing (no decoding); stops quietly at a cut tail."""
    out = DecodedIndex()
    with av.open(str(path)) as c:
        try:
            for pkt in c.demux(video=0):
                if pkt.pts is None:
                    continue
                out.pts.append(int(pkt.pts))
                if pkt.is_keyframe:
                    out.keyframes.append(int(pkt.pts))
        except av.error.InvalidDataError:
            pass
    return out


class SegmentMuxer:
    """One open segment file: starts on `first` (a keyframe), then takes packets of the same camera."""

    def __init__(self, path: Path, first: EncodedFrame):
        if not first.keyframe:
            raise ValueError("a segment starts on a keyframe")
        path.parent.mkdir(parents=True, exist_ok=True)
        width, height = frame_size(first.data)
        self.path, self.start_pts = path, first.pts
        # flush_packets: each fragment reaches the file when it is complete (a crash loses only the open one)
        self.container = av.open(str(path), "w", format="mp4", options={"movflags": MOVFLAGS, "flush_packets": "1"})
        st = self.container.add_stream("h264")
        st.width, st.height = width, height
        st.time_base = Fraction(1, CLOCK_HZ)
        st.codec_context.extradata = parameter_sets(first.data)
        self.stream = st
        self.offsets: list[int] = []
        self.frame_nos: list[int] = []
        self.keyframes: list[int] = []
        self.last_captured_at = first.captured_at
        self.write(first)

    def write(self, ef: EncodedFrame) -> None:
        off = ef.pts - self.start_pts
        if self.offsets and off <= self.offsets[-1]:
            return  # a repeated or older time cannot follow in an MP4 track
        pkt = av.Packet(ef.data)
        pkt.pts = pkt.dts = off
        pkt.time_base = Fraction(1, CLOCK_HZ)
        pkt.stream = self.stream
        pkt.is_keyframe = ef.keyframe
        self.container.mux(pkt)
        self.offsets.append(off)
        self.frame_nos.append(ef.frame_no)
        if ef.keyframe:
            self.keyframes.append(off)
        self.last_captured_at = ef.captured_at

    def close(self) -> int:
        """Finish the file (its last fragment and index); returns its size in bytes."""
        self.container.close()
        return self.path.stat().st_size
