"""Tests of tracker.sources with real H.264 files written here, and of the opening errors."""

from __future__ import annotations

import socket
import threading
from fractions import Fraction
from pathlib import Path

import av
import cv2
import numpy as np
import pytest

from tracker.frames import StereoFrame
from tracker.sources import (
    CameraPair,
    RtspPair,
    SourceError,
    VideoFilePair,
    _CapturePair,
    open_source,
)

W, H = 96, 64  # even sizes for yuv420p
FPS = 25


def pattern(i: int, invert: bool = False) -> np.ndarray:
    """Frame i: grey level 40 + 4 i with a white 8x8 block whose column encodes i (frame counter)."""
    img = np.full((H, W), 40 + 4 * i, np.uint8)
    x = 8 * (i % 11)
    img[16:24, x : x + 8] = 250
    return 255 - img if invert else img


def write_video(path: Path, n: int, *, invert: bool = False, pts_offset_ms: int = 0, size=(W, H)) -> Path:
    """Encode n frames of `pattern` with libx264 (yuv420p) at 25 fps, PTS in ms shifted by pts_offset_ms."""
    tb = Fraction(1, 1000)
    with av.open(str(path), "w") as container:
        stream = container.add_stream("libx264", rate=FPS)
        stream.width, stream.height = size
        stream.pix_fmt = "yuv420p"
        stream.codec_context.time_base = tb
        stream.options = {"preset": "ultrafast", "qp": "4"}
        for i in range(n):
            img = cv2.resize(pattern(i, invert), size, interpolation=cv2.INTER_NEAREST)
            frame = av.VideoFrame.from_ndarray(img, format="gray")
            frame.pts, frame.time_base = i * 1000 // FPS + pts_offset_ms, tb
            for packet in stream.encode(frame):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
    return path


def read_all(source) -> list[StereoFrame]:
    frames = []
    while (f := source.read()) is not None:
        frames.append(f)
        assert len(frames) < 1000
    assert source.read() is None  # stays at the end
    return frames


def check_content(f: StereoFrame) -> None:
    i = f.index
    assert f.left.dtype == np.uint8 and f.left.shape == (H, W) and f.right.shape == (H, W)
    assert abs(float(np.median(f.left)) - (40 + 4 * i)) <= 3
    assert abs(float(np.median(f.right)) - (255 - 40 - 4 * i)) <= 3
    x = 8 * (i % 11)
    assert f.left[17:23, x + 1 : x + 7].min() > 200  # the counter block is where frame i puts it
    assert f.right[17:23, x + 1 : x + 7].max() < 55


def test_video_file_pair_frames_timestamps_and_offset(tmp_path: Path) -> None:
    left = write_video(tmp_path / "left.mp4", 30)
    right = write_video(tmp_path / "right.mp4", 30, invert=True, pts_offset_ms=7)
    with VideoFilePair(left, right) as src:
        frames = read_all(src)
    assert [f.index for f in frames] == list(range(30))
    for f in frames:
        check_content(f)
        assert f.offset_s == pytest.approx(0.007, abs=1e-4)
    t = np.array([f.t_left for f in frames])
    assert np.all(np.diff(t) > 0)
    assert np.diff(t) == pytest.approx(1.0 / FPS, abs=1e-3)


def test_video_files_of_different_length_end_with_the_shorter(tmp_path: Path) -> None:
    src = open_source(
        "files", [str(write_video(tmp_path / "l.mkv", 12)), str(write_video(tmp_path / "r.mkv", 20))]
    )
    assert len(read_all(src)) == 12
    src.close()


def test_capture_pair_grabs_then_retrieves_with_monotonic_times(tmp_path: Path) -> None:
    """The live-source logic (grab both, retrieve both, grey conversion) run on cv2.VideoCapture files."""
    left = write_video(tmp_path / "left.mp4", 15)
    right = write_video(tmp_path / "right.mp4", 15, invert=True)
    pair = _CapturePair(cv2.VideoCapture(str(left)), cv2.VideoCapture(str(right)), ("left", "right"))
    with pair:
        frames = read_all(pair)
    assert len(frames) == 15
    for f in frames:
        check_content(f)
        assert f.t_right >= f.t_left
    assert np.all(np.diff([f.t_left for f in frames]) > 0)


def test_mismatched_video_sizes(tmp_path: Path) -> None:
    left = write_video(tmp_path / "left.mp4", 5)
    right = write_video(tmp_path / "right.mp4", 5, size=(128, 64))
    with pytest.raises(SourceError, match=r"differ in size: 96x64 vs 128x64"):
        VideoFilePair(left, right)


def test_missing_and_non_video_files(tmp_path: Path) -> None:
    good = write_video(tmp_path / "ok.mp4", 3)
    with pytest.raises(SourceError, match=r"^cannot open left video /x/y\.mp4: no such file$"):
        VideoFilePair("/x/y.mp4", good)
    missing = tmp_path / "nope.mp4"
    with pytest.raises(SourceError, match=f"cannot open right video {missing}: no such file"):
        VideoFilePair(good, missing)
    text = tmp_path / "notes.mp4"
    text.write_text("this is not a video\n" * 50)
    with pytest.raises(SourceError, match=f"cannot open left video {text}: not a readable video"):
        open_source("files", [str(text), str(good)])
    with pytest.raises(SourceError, match="is a directory"):
        VideoFilePair(tmp_path, good)


def test_missing_camera_devices() -> None:
    with pytest.raises(SourceError, match=r"^cannot open left camera /dev/video99: no such device$"):
        CameraPair("/dev/video99", "/dev/video98")
    with pytest.raises(SourceError, match="cannot open left camera 99"):
        open_source("usb", ["99", "98"])


def test_unreachable_rtsp_fails_with_a_message() -> None:
    with pytest.raises(SourceError, match=r"cannot open left stream rtsp://127\.0\.0\.1:9/x: .*unreachable"):
        open_source("rtsp", ["rtsp://127.0.0.1:9/x", "rtsp://127.0.0.1:9/y"])
    with pytest.raises(SourceError, match="not a network URL"):
        RtspPair("/tmp/file.mp4", "rtsp://127.0.0.1:9/y")


def test_silent_rtsp_server_times_out() -> None:
    """A port that accepts TCP but never answers RTSP: the FFmpeg open timeout ends the attempt."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(4)
    port = server.getsockname()[1]
    accepted: list[socket.socket] = []
    stop = threading.Event()

    def serve() -> None:
        server.settimeout(0.1)
        while not stop.is_set():
            try:
                accepted.append(server.accept()[0])
            except OSError:
                continue

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    try:
        with pytest.raises(SourceError, match=f"cannot open left stream rtsp://127.0.0.1:{port}/x"):
            RtspPair(f"rtsp://127.0.0.1:{port}/x", f"rtsp://127.0.0.1:{port}/y", timeout_s=1.0)
    finally:
        stop.set()
        thread.join()
        for conn in accepted:
            conn.close()
        server.close()


def test_factory_argument_errors() -> None:
    with pytest.raises(SourceError, match="unknown source kind 'sim2'"):
        open_source("sim2", ["a", "b"])
    with pytest.raises(SourceError, match="needs 2 arguments"):
        open_source("files", ["only-one.mp4"])


def write_colour_video(path: Path, n: int, size=(W, H), fmt: str = "yuv420p", codec: str = "libx264") -> Path:
    """n frames: blue (BGR 200, 60, 20) with a red block (BGR 30, 30, 220) at the top left quarter."""
    w, h = size
    img = np.empty((h, w, 3), np.uint8)
    img[:] = (200, 60, 20)
    img[: h // 2, : w // 2] = (30, 30, 220)
    with av.open(str(path), "w") as container:
        stream = container.add_stream(codec, rate=FPS)
        stream.width, stream.height = size
        stream.pix_fmt = fmt
        if codec == "libx264":
            stream.options = {"preset": "ultrafast", "qp": "4"}
        for i in range(n):
            frame = av.VideoFrame.from_ndarray(img, format="bgr24").reformat(format=fmt)
            frame.pts = i
            for packet in stream.encode(frame):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
    return path


def check_colour(f: StereoFrame) -> None:
    """The colour images are BGR (H, W, 3) of the video's colours; the tracker's images are their grey."""
    for grey, bgr in ((f.left, f.left_colour), (f.right, f.right_colour)):
        assert bgr is not None and bgr.shape == (H, W, 3) and bgr.dtype == np.uint8
        assert np.abs(bgr[4, 4].astype(int) - (30, 30, 220)).max() <= 12  # red
        assert np.abs(bgr[-4, -4].astype(int) - (200, 60, 20)).max() <= 12  # blue
        want = cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY)
        assert grey.shape == (H, W) and np.abs(grey.astype(int) - want.astype(int)).max() <= 1


def test_colour_videos_keep_colour_for_viewing_and_grey_for_the_tracker(tmp_path: Path) -> None:
    left, right = write_colour_video(tmp_path / "l.mp4", 5), write_colour_video(tmp_path / "r.mp4", 5)
    with VideoFilePair(left, right) as src:
        frames = read_all(src)
    assert len(frames) == 5
    for f in frames:
        check_colour(f)
    with _CapturePair(cv2.VideoCapture(str(left)), cv2.VideoCapture(str(right)), ("left", "right")) as pair:
        frames = read_all(pair)
    assert len(frames) == 5
    for f in frames:
        check_colour(f)


def test_grey_videos_have_no_colour_images(tmp_path: Path) -> None:
    left = write_colour_video(tmp_path / "l.mkv", 3, fmt="gray", codec="ffv1")
    right = write_colour_video(tmp_path / "r.mkv", 3, fmt="gray", codec="ffv1")
    with VideoFilePair(left, right) as src:
        frames = read_all(src)
    assert len(frames) == 3
    assert all(f.left_colour is None and f.right_colour is None for f in frames)
