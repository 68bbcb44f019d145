"""The playback frame cache on a real fragmented MP4 segment: every frame's JPEG is the frame of its stamp,
stepping forward through a keyframe group decodes on from where the decoder stopped (one seek per group),
a jump to another group seeks in the file already open, a frame of the group last decoded is cached, and a
frame past the file is NotFound."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
from test_fmp4 import packets

from server.services.errors import NotFound
from server.services.playback import FrameCache, FrameRef
from tmeye.media.encoder import read_stamp
from tmeye.media.fmp4 import SegmentMuxer


def segment(tmp_path: Path) -> tuple[list[int], list[int], list[int]]:
    """A 60-frame segment with a keyframe every 15 frames: (offsets, keyframe offsets, frame numbers)."""
    pk = packets(60)
    mux = SegmentMuxer(tmp_path / "s.mp4", pk[0])
    for p in pk[1:]:
        mux.write(p)
    mux.close()
    return mux.offsets, mux.keyframes, [p.frame_no for p in pk]


def ref(offsets: list[int], keys: list[int], nos: list[int], i: int) -> FrameRef:
    key = max(k for k in keys if k <= offsets[i])
    return FrameRef(1, "s.mp4", offsets[i], key, nos[i], 0.0)


def stamp_of(data: bytes) -> int:
    return read_stamp(np.asarray(cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_GRAYSCALE), np.uint8))


def test_forward_steps_decode_on_and_jumps_seek(tmp_path: Path) -> None:
    offs, keys, nos = segment(tmp_path)
    cache = FrameCache(tmp_path, groups=1, jpegs=1)
    for i in range(15, 30):  # one group, frame by frame: a single seek
        assert stamp_of(cache.jpeg(ref(offs, keys, nos, i)).data) == nos[i]
    assert cache.decoded_groups == 1
    assert stamp_of(cache.jpeg(ref(offs, keys, nos, 31)).data) == nos[31]  # the next group: from its keyframe
    assert cache.decoded_groups == 2
    for i in (50, 5, 44):  # jumps: each a seek in the open file, the frame exact
        assert stamp_of(cache.jpeg(ref(offs, keys, nos, i)).data) == nos[i]
    assert cache.decoded_groups == 5
    assert stamp_of(cache.jpeg(ref(offs, keys, nos, 33)).data) == nos[33]  # back in the group just decoded: cached
    assert cache.decoded_groups == 5
    with pytest.raises(NotFound):
        cache.jpeg(FrameRef(1, "s.mp4", offs[-1] + 3000, keys[-1], -1, 0.0))
