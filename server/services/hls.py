"""The HLS playlist (version 7, fMP4) of a run of segment files: each file's ftyp+moov is its EXT-X-MAP
and each moof+mdat fragment (one keyframe group) a media segment addressed by byte range, so hls.js seeks
to any keyframe group. Files restart their time at 0: each begins with EXT-X-DISCONTINUITY and carries its
wall-clock start as EXT-X-PROGRAM-DATE-TIME."""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from pathlib import Path

from server.db.models import Segment
from server.services.errors import NotFound
from tmeye.media.encoder import CLOCK_HZ
from tmeye.media.fmp4 import layout


def _iso(t: float) -> str:
    return time.strftime("%Y-%m-%dT%H:%M:%S", time.gmtime(t)) + f".{int(round((t % 1) * 1000)) % 1000:03d}Z"


def _durations(seg: Segment, parts: int) -> list[float]:
    """Durations (s) of the fragments: keyframe to keyframe, the last one to the end plus a frame."""
    offs = seg.frame_offsets
    period = offs[-1] / (len(offs) - 1) / CLOCK_HZ if len(offs) > 1 else 1 / 30
    total = offs[-1] / CLOCK_HZ + period if offs else period
    keys = list(seg.keyframes)
    if parts != len(keys):
        return [total]
    return [b - a for a, b in zip(keys, [*keys[1:], total], strict=True)]


def playlist(segs: Sequence[Segment], data_dir: Path) -> str:
    lines: list[str] = []
    longest = 1.0
    for seg in segs:
        if not seg.frame_offsets:
            continue
        lay = layout(data_dir / seg.path)
        if not lay.fragments:
            continue
        uri = f"/api/recordings/{seg.id}/file"
        durs = _durations(seg, len(lay.fragments))
        frags = lay.fragments if len(durs) == len(lay.fragments) else [(lay.init_bytes, lay.length - lay.init_bytes)]
        lines += ["#EXT-X-DISCONTINUITY"] if lines else []
        lines += [f'#EXT-X-MAP:URI="{uri}",BYTERANGE="{lay.init_bytes}@0"',
                  f"#EXT-X-PROGRAM-DATE-TIME:{_iso(seg.start)}"]
        for (off, n), d in zip(frags, durs, strict=True):
            lines += [f"#EXTINF:{d:.6f},", f"#EXT-X-BYTERANGE:{n}@{off}", uri]
            longest = max(longest, d)
    if not lines:
        raise NotFound("no finished recording in that range")
    head = ["#EXTM3U", "#EXT-X-VERSION:7", f"#EXT-X-TARGETDURATION:{math.ceil(longest)}", "#EXT-X-MEDIA-SEQUENCE:0",
            "#EXT-X-PLAYLIST-TYPE:VOD", "#EXT-X-INDEPENDENT-SEGMENTS"]
    return "\n".join([*head, *lines, "#EXT-X-ENDLIST", ""])
