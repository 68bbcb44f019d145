"""Fragmented MP4 segments from encoded packets: written without encoding again, decoded back with PyAV,
and a file cut mid-fragment (as by a crash) truncated to its last complete fragment."""

from __future__ import annotations

import os
from pathlib import Path

import av
import numpy as np
import pytest

from tmeye.media.encoder import CLOCK_HZ, EncodedFrame, H264Encoder, pts_of, read_stamp, stamp
from tmeye.media.fmp4 import SegmentMuxer, index_file, layout, parameter_sets, truncate_to_fragments

T0 = 1_795_000_000.0


def packets(n: int, gop: int = 15) -> list[EncodedFrame]:
    enc = H264Encoder(320, 240, 30.0, 500_000, gop)
    rng = np.random.default_rng(1)
    out = []
    for i in range(n):
        img = stamp((rng.random((240, 320)) * 60).astype(np.uint8), 1000 + i)
        t = T0 + i / 30
        for data, pts, key in enc.encode(img, pts_of(t), i == 0):
            out.append(EncodedFrame("left", data, pts, key, 1000 + i, t))
    return out


def decode(path: Path) -> list[tuple[int, int]]:
    got = []
    with av.open(str(path)) as c:
        try:
            for f in c.decode(video=0):
                got.append((int(f.pts), read_stamp(f.to_ndarray(format="gray"))))
        except av.error.InvalidDataError:
            pass
    return got


def test_segment_decodes_with_stamps_and_times(tmp_path: Path) -> None:
    pk = packets(60)
    mux = SegmentMuxer(tmp_path / "a.mp4", pk[0])
    for p in pk[1:]:
        mux.write(p)
    mux.close()
    got = decode(tmp_path / "a.mp4")
    assert [s for _, s in got] == [p.frame_no for p in pk]
    assert [t for t, _ in got] == [p.pts - pk[0].pts for p in pk] == mux.offsets
    assert mux.keyframes == [p.pts - pk[0].pts for p in pk if p.keyframe] and len(mux.keyframes) == 4
    lay = layout(tmp_path / "a.mp4")
    assert len(lay.fragments) == 4 and lay.init_bytes > 0
    assert abs(mux.offsets[1] / CLOCK_HZ - 1 / 30) < 1e-4


def test_cut_file_keeps_complete_fragments(tmp_path: Path) -> None:
    pk = packets(50)
    path = tmp_path / "b.mp4"
    mux = SegmentMuxer(path, pk[0])
    for p in pk[1:]:
        mux.write(p)
    complete = layout(path)  # fragments are flushed when complete: 3 of them (frames 0-44)
    assert len(complete.fragments) == 3
    mux.container.close()
    os.truncate(path, complete.length + 700)  # the open fragment cut in its middle
    assert truncate_to_fragments(path) == complete.length
    assert [s for _, s in decode(path)] == [p.frame_no for p in pk[:45]]
    assert len(index_file(path).pts) == 45


def test_parameter_sets_need_a_keyframe() -> None:
    pk = packets(3)
    assert parameter_sets(pk[0].data).startswith(b"\x00\x00\x00\x01")
    with pytest.raises(ValueError, match="SPS"):
        parameter_sets(pk[1].data)
    with pytest.raises(ValueError, match="keyframe"):
        SegmentMuxer(Path("/nonexistent/x.mp4"), pk[1])
