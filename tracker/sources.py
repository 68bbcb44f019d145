"""Frame sources for real input: video file pairs, USB/V4L2 camera pairs and RTSP stream pairs.

Each implements tracker.frames.FrameSource: `read()` returns the next StereoFrame (grey uint8 (H, W)
images) or None at the end of the input, `close()` releases it; sources are also context managers.
Opening problems (missing file or device, not a video, unreachable stream, left/right size mismatch)
raise SourceError with a one-line message naming the input.

Timing: video files report each frame's presentation timestamp (seconds, from the stream's PTS), so
StereoFrame.offset_s is the left/right offset recorded in the files; live sources grab both cameras
first and retrieve (decode) afterwards, stamping each grab with time.monotonic() in seconds.
"""

from __future__ import annotations

import contextlib
import os
import socket
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from types import TracebackType
from typing import Self
from urllib.parse import urlsplit

import av
import cv2
import numpy as np

from tracker.frames import U8, FrameSource, StereoFrame

SOURCE_KINDS = ("files", "usb", "rtsp")


class SourceError(ValueError):
    """A frame source cannot be opened or read; the message names the input and the reason."""


def _to_grey(img: np.ndarray) -> U8:
    """Any OpenCV frame (grey, BGR or BGRA; uint8 or uint16) -> grey uint8 (H, W)."""
    if img.dtype == np.uint16:
        img = (img >> 8).astype(np.uint8)
    if img.ndim == 3 and img.shape[2] == 1:
        img = img[:, :, 0]
    if img.ndim == 3:
        code = cv2.COLOR_BGRA2GRAY if img.shape[2] == 4 else cv2.COLOR_BGR2GRAY
        img = cv2.cvtColor(img, code)
    return np.ascontiguousarray(img, dtype=np.uint8)


def _to_bgr(img: np.ndarray) -> U8 | None:
    """A colour OpenCV frame (BGR or BGRA; uint8 or uint16) -> BGR uint8 (H, W, 3); None for a grey one."""
    if img.ndim != 3 or img.shape[2] not in (3, 4):
        return None
    if img.dtype == np.uint16:
        img = (img >> 8).astype(np.uint8)
    if img.shape[2] == 4:
        img = cv2.cvtColor(img, cv2.COLOR_BGRA2BGR)
    return np.ascontiguousarray(img, dtype=np.uint8)


def _check_sizes(what: str, left: tuple[int, int], right: tuple[int, int]) -> None:
    """Raise SourceError if the left and right (width, height) differ."""
    if left != right:
        raise SourceError(
            f"left and right {what} differ in size: {left[0]}x{left[1]} vs {right[0]}x{right[1]} (W x H)"
        )


class _Base:
    """Context-manager plumbing shared by the sources."""

    def close(self) -> None:  # pragma: no cover - overridden
        raise NotImplementedError

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()


class _VideoFile:
    """One video file decoded with PyAV: grey frames with their presentation times in seconds."""

    def __init__(self, path: str | Path, side: str) -> None:
        self.path = Path(path)
        self.label = f"{side} video {self.path}"
        if not self.path.exists():
            raise SourceError(f"cannot open {self.label}: no such file")
        if self.path.is_dir():
            raise SourceError(f"cannot open {self.label}: it is a directory")
        try:
            self.container = av.open(str(self.path), "r")
        except (av.FFmpegError, OSError, UnicodeDecodeError) as exc:
            raise SourceError(f"cannot open {self.label}: not a readable video ({_reason(exc)})") from None
        if not self.container.streams.video:
            self.container.close()
            raise SourceError(f"cannot open {self.label}: it has no video stream")
        self.stream = self.container.streams.video[0]
        self.size = (int(self.stream.codec_context.width), int(self.stream.codec_context.height))
        rate = self.stream.average_rate or self.stream.guessed_rate
        self.period = 1.0 / float(rate) if rate else 0.0
        pix_fmt = str(self.stream.codec_context.pix_fmt or "")
        self.colour = not (pix_fmt.startswith(("gray", "mono", "ya")) or pix_fmt in ("", "pal8"))
        self._frames = self.container.decode(self.stream)
        self._count = 0

    def read(self) -> tuple[U8, float, U8 | None] | None:
        """Next (grey image (H, W), presentation time in s, BGR image (H, W, 3) of a colour video or None),
        or None at the end of the file."""
        try:
            frame = next(self._frames)
        except StopIteration:
            return None
        except (av.FFmpegError, OSError) as exc:
            raise SourceError(
                f"cannot decode {self.label} after frame {self._count}: {_reason(exc)}"
            ) from None
        t = frame.time if frame.time is not None else self._count * self.period
        self._count += 1
        if self.colour:
            bgr = np.ascontiguousarray(frame.to_ndarray(format="bgr24"), dtype=np.uint8)
            return np.asarray(cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY), np.uint8), float(t), bgr
        return np.ascontiguousarray(frame.to_ndarray(format="gray"), dtype=np.uint8), float(t), None

    def close(self) -> None:
        self.container.close()


def _reason(exc: BaseException) -> str:
    """A short one-line reason for an exception."""
    text = getattr(exc, "strerror", None) or str(exc) or type(exc).__name__
    return " ".join(str(text).split())


class VideoFilePair(_Base):
    """Left and right video files (any container/codec FFmpeg reads), decoded to grey uint8 in step.

    Timestamps are the frames' presentation times in seconds; StereoFrame.offset_s reports the recorded
    right-minus-left offset. read() returns None when either file ends.
    """

    def __init__(self, left_path: str | Path, right_path: str | Path) -> None:
        self._left = _VideoFile(left_path, "left")
        try:
            self._right = _VideoFile(right_path, "right")
            _check_sizes("videos", self._left.size, self._right.size)
        except SourceError:
            self._left.close()
            if hasattr(self, "_right"):
                self._right.close()
            raise
        self._index = 0

    def read(self) -> StereoFrame | None:
        left, right = self._left.read(), self._right.read()
        if left is None or right is None:
            return None
        if left[0].shape != right[0].shape:
            _check_sizes("video frames", left[0].shape[::-1], right[0].shape[::-1])
        frame = StereoFrame(self._index, left[0], right[0], t_left=left[1], t_right=right[1],
                            left_colour=left[2], right_colour=right[2])
        self._index += 1
        return frame

    def close(self) -> None:
        self._left.close()
        self._right.close()


class _CapturePair(_Base):
    """Two cv2.VideoCapture inputs read in step: grab both, then retrieve both."""

    def __init__(self, left: cv2.VideoCapture, right: cv2.VideoCapture, labels: tuple[str, str]) -> None:
        self._caps = (left, right)
        self._labels = labels
        self._index = 0

    def read(self) -> StereoFrame | None:
        left, right = self._caps
        if not left.grab():
            return None
        t_left = time.monotonic()
        if not right.grab():
            return None
        t_right = time.monotonic()
        ok_l, img_l = left.retrieve()
        ok_r, img_r = right.retrieve()
        if not ok_l or not ok_r or img_l is None or img_r is None:
            return None
        gl, gr = _to_grey(np.asarray(img_l)), _to_grey(np.asarray(img_r))
        if gl.shape != gr.shape:
            _check_sizes(f"frames of {self._labels[0]} / {self._labels[1]}", gl.shape[::-1], gr.shape[::-1])
        cl, cr = _to_bgr(np.asarray(img_l)), _to_bgr(np.asarray(img_r))
        if cl is None or cr is None:  # colour for viewing only when both cameras give it
            cl = cr = None
        frame = StereoFrame(self._index, gl, gr, t_left=t_left, t_right=t_right, left_colour=cl, right_colour=cr)
        self._index += 1
        return frame

    def close(self) -> None:
        for cap in self._caps:
            cap.release()


def _quiet_opencv() -> contextlib.AbstractContextManager[None]:
    """Silence OpenCV's own warning log (e.g. 'can't open camera by index') while opening."""
    logging = getattr(getattr(cv2, "utils", None), "logging", None)
    if logging is None or not hasattr(logging, "setLogLevel"):
        return contextlib.nullcontext()

    @contextlib.contextmanager
    def quiet() -> Iterator[None]:
        old = logging.getLogLevel()
        logging.setLogLevel(logging.LOG_LEVEL_ERROR)
        try:
            yield
        finally:
            logging.setLogLevel(old)

    return quiet()


def _open_camera(device: int | str, side: str) -> cv2.VideoCapture:
    """Open one USB/V4L2 camera by index or device path; SourceError if it cannot be opened."""
    label = f"{side} camera {device}"
    if isinstance(device, str):
        if not os.path.exists(device):
            raise SourceError(f"cannot open {label}: no such device")
        target: int | str = device
    else:
        if device < 0:
            raise SourceError(f"cannot open {label}: camera index must be >= 0")
        if sys.platform.startswith("linux") and not os.path.exists(f"/dev/video{device}"):
            raise SourceError(f"cannot open {label}: no such device (/dev/video{device})")
        target = device
    with _quiet_opencv():
        cap = cv2.VideoCapture(target)
    if not cap.isOpened():
        cap.release()
        raise SourceError(f"cannot open {label}: the device did not open (busy, or not a camera)")
    return cap


class CameraPair(_CapturePair):
    """Two USB/V4L2 cameras, by index (0, 1, ...) or device path (/dev/video0). Frames are stamped with
    time.monotonic() (s) right after each grab; both are grabbed before either is decoded."""

    def __init__(self, left: int | str, right: int | str) -> None:
        cap_l = _open_camera(left, "left")
        try:
            cap_r = _open_camera(right, "right")
        except SourceError:
            cap_l.release()
            raise
        super().__init__(cap_l, cap_r, (f"camera {left}", f"camera {right}"))


def _probe_tcp(url: str, label: str, timeout_s: float) -> None:
    """Fail fast with SourceError if the URL's host:port does not accept a TCP connection."""
    parts = urlsplit(url)
    default = {"rtsp": 554, "rtsps": 322, "http": 80, "https": 443, "rtmp": 1935}.get(parts.scheme)
    try:
        port = parts.port or default
    except ValueError:
        raise SourceError(f"cannot open {label}: bad port in the URL") from None
    if not parts.hostname or port is None:
        raise SourceError(f"cannot open {label}: not a network URL with a host (e.g. rtsp://host:554/path)")
    try:
        with socket.create_connection((parts.hostname, port), timeout=timeout_s):
            pass
    except OSError as exc:
        raise SourceError(
            f"cannot open {label}: {parts.hostname}:{port} unreachable ({_reason(exc)})"
        ) from None


def _open_stream(url: str, side: str, timeout_s: float) -> cv2.VideoCapture:
    """Open one network stream with FFmpeg and bounded open/read timeouts."""
    label = f"{side} stream {url}"
    _probe_tcp(url, label, timeout_s)
    ms = int(timeout_s * 1000)
    params = [cv2.CAP_PROP_OPEN_TIMEOUT_MSEC, ms, cv2.CAP_PROP_READ_TIMEOUT_MSEC, ms]
    with _quiet_opencv():
        cap = cv2.VideoCapture(url, cv2.CAP_FFMPEG, params)
    if not cap.isOpened():
        cap.release()
        raise SourceError(f"cannot open {label}: FFmpeg could not open the stream within {timeout_s:g} s")
    return cap


class RtspPair(_CapturePair):
    """Two RTSP (or other FFmpeg network) streams. Frames are stamped with time.monotonic() (s) at grab.
    timeout_s bounds the TCP probe, the FFmpeg open and each read."""

    def __init__(self, url_left: str, url_right: str, *, timeout_s: float = 5.0) -> None:
        cap_l = _open_stream(url_left, "left", timeout_s)
        try:
            cap_r = _open_stream(url_right, "right", timeout_s)
        except SourceError:
            cap_l.release()
            raise
        super().__init__(cap_l, cap_r, (f"stream {url_left}", f"stream {url_right}"))


def _device(arg: str) -> int | str:
    """'0' -> camera index 0; anything else (e.g. /dev/video2) is a device path."""
    return int(arg) if arg.isdigit() else arg


def open_source(kind: str, args: list[str]) -> FrameSource:
    """Frame source factory: 'files' LEFT RIGHT (video paths), 'usb' LEFT RIGHT (camera index or device
    path), 'rtsp' LEFT_URL RIGHT_URL. Raises SourceError with a one-line message on any problem."""
    if kind not in SOURCE_KINDS:
        raise SourceError(f"unknown source kind {kind!r} (expected one of: {', '.join(SOURCE_KINDS)})")
    if len(args) != 2:
        raise SourceError(f"source {kind!r} needs 2 arguments (left, right), got {len(args)}: {args}")
    left, right = args
    if kind == "files":
        return VideoFilePair(left, right)
    if kind == "usb":
        return CameraPair(_device(left), _device(right))
    return RtspPair(left, right)
