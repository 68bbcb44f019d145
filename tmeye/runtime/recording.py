"""A frame source over recordings (`tmeye track --source recording`, `POST /api/replays`): both cameras'
H.264 segments of a time range decoded in step, frames paired by their recorded capture clock (the 90 kHz
pts that is also the key of each frame's recorded telemetry), converted to grey for the tracker (colour is
kept for nothing else). Each frame carries the mount pose recorded with it (the telemetry's servo angles),
so the pipeline localises as it did live; no servo is driven.

The segment rows and the telemetry are read with the standard library's sqlite3 (read only): the runtime's
source layer stays free of the server's database code. Problems a user can fix raise `RecordingError`
with one line (nothing recorded in the range, end before start, a data directory without a database).
"""

from __future__ import annotations

import json
import math
import sqlite3
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import av
import numpy as np
from numpy.typing import NDArray

from tracker.frames import GimbalState, StereoFrame

CLOCK_HZ = 90000  # the recordings' capture clock (tmeye.media.encoder.CLOCK_HZ)
CAMERAS = ("left", "right")
U8 = NDArray[np.uint8]


class RecordingError(ValueError):
    """The recordings cannot be replayed as asked; the message is one line."""


@dataclass(frozen=True)
class RecordedTelemetry:
    """What was recorded with one frame: its runtime index, capture time (Unix s), mount pose (None when no
    mount was driven) and the whole live telemetry message."""

    frame_no: int
    captured_at: float
    gimbal: GimbalState | None
    data: dict[str, Any]


def _connect(data_dir: Path) -> sqlite3.Connection:
    db = data_dir / "tmeye.db"
    if not db.is_file():
        raise RecordingError(f"no database in {data_dir} (not a tmeye data directory)")
    return sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=10.0)


def plan(data_dir: Path, start: float, end: float) -> dict[str, list[tuple[str, int]]]:
    """Per camera, the finished segments (path, start pts) overlapping start..end (Unix s), in time order.
    RecordingError when end is not after start or a camera has nothing recorded there."""
    if not end > start:
        raise RecordingError(f"end ({end:.3f}) must be after start ({start:.3f})")
    con = _connect(data_dir)
    try:
        out = {c: [(str(p), int(s)) for p, s in con.execute(
            "SELECT path, start_pts FROM segments WHERE camera = ? AND status != 'open' AND start <= ? AND end >= ?"
            " ORDER BY start", (c, end, start))] for c in CAMERAS}
    except sqlite3.Error as exc:
        raise RecordingError(f"cannot read the recordings of {data_dir}: {exc}") from None
    finally:
        con.close()
    missing = [c for c in CAMERAS if not out[c]]
    if missing:
        raise RecordingError(f"nothing of the {' and '.join(missing)} camera was recorded between "
                             f"{start:.3f} and {end:.3f}")
    return out


def recorded_telemetry(data_dir: Path, start: float, end: float) -> dict[int, RecordedTelemetry]:
    """The recorded telemetry of start..end keyed by pts (90 kHz ticks of the capture time)."""
    con = _connect(data_dir)
    try:
        rows = con.execute("SELECT pts, frame_no, captured_at, data FROM recorded_frames "
                           "WHERE captured_at >= ? AND captured_at <= ? ORDER BY pts", (start, end)).fetchall()
    finally:
        con.close()
    out = {}
    for pts, no, at, data in rows:
        tm = json.loads(data) if isinstance(data, str) else dict(data)
        servo = tm.get("servo")
        g = GimbalState(float(servo["pan_deg"]), float(servo["tilt_deg"])) if servo else None
        out[int(pts)] = RecordedTelemetry(int(no), float(at), g, tm)
    return out


def _decode(data_dir: Path, segs: list[tuple[str, int]]) -> Iterator[tuple[int, av.VideoFrame]]:
    """(absolute pts, frame) of a camera's segments in order; a frame held by two segments comes once; a
    segment cut by a crash ends at its last complete fragment."""
    last = -1
    for path, start_pts in segs:
        with av.open(str(data_dir / path)) as c:
            st = c.streams.video[0]
            st.thread_type = "AUTO"
            try:
                for frame in c.decode(st):
                    if frame.pts is None or (pts := start_pts + int(frame.pts)) <= last:
                        continue
                    last = pts
                    yield pts, frame
            except av.error.InvalidDataError:
                continue


def _frame_time(tm: RecordedTelemetry) -> tuple[float, float]:
    """The times the live tracker was given for a recorded frame: (t, right - left offset) in s, from its
    telemetry (the simulator's scene time, a camera's monotonic clock); the capture time (Unix s) where a
    recording has none. The tracker's velocities come from these: the capture times, stamped by the wall
    clock after the frame was made, jitter by milliseconds under load, and the replay would track
    differently from the live run."""
    t, offset = tm.data.get("t"), tm.data.get("offset_s", 0.0)
    if isinstance(t, (int, float)) and math.isfinite(t) and isinstance(offset, (int, float)) and math.isfinite(offset):
        return float(t), float(offset)
    return tm.captured_at, 0.0


class RecordingSource:
    """FrameSource over the recordings of start..end (Unix s) in `data_dir`. A pair is read when both
    cameras decoded a frame of the same pts that has recorded telemetry (a frame only one camera
    recorded is skipped and counted). `index` of a frame: its recorded runtime frame number; its times:
    those the live tracker had (`_frame_time`); `captured_at`: the recorded capture time (Unix s) of the
    pair read last."""

    def __init__(self, data_dir: Path, start: float, end: float):
        self.data_dir, self.start, self.end = data_dir, start, end
        segs = plan(data_dir, start, end)
        self.telemetry = recorded_telemetry(data_dir, start, end)
        if not self.telemetry:
            raise RecordingError(f"no recorded telemetry between {start:.3f} and {end:.3f}")
        self.total = len(self.telemetry)
        self.t0, self.t1 = round(start * CLOCK_HZ), round(end * CLOCK_HZ)
        self._its = {c: _decode(data_dir, segs[c]) for c in CAMERAS}
        self.read_pairs = self.unpaired = 0
        self.captured_at = math.nan  # the recorded capture time (Unix s) of the pair read last
        self.fps = self._fps()

    def _fps(self) -> float:
        ts = sorted(t.captured_at for t in self.telemetry.values())
        gaps = np.diff(ts)
        return float(1.0 / np.median(gaps)) if gaps.size and np.median(gaps) > 0 else 30.0

    def mount_poses(self) -> list[GimbalState]:
        """The recorded mount poses of the range (empty when no mount was driven)."""
        return [t.gimbal for t in self.telemetry.values() if t.gimbal is not None]

    def _next(self, camera: str) -> tuple[int, av.VideoFrame] | None:
        for pts, frame in self._its[camera]:
            if pts > self.t1:
                return None
            if pts >= self.t0:
                return pts, frame
        return None

    def read(self) -> StereoFrame | None:
        a, b = self._next("left"), self._next("right")
        while a is not None and b is not None:
            if a[0] == b[0] and a[0] in self.telemetry:
                return self._pair(a[0], a[1], b[1])
            self.unpaired += 1
            if a[0] <= b[0]:
                a = self._next("left")
            else:
                b = self._next("right")
        return None

    def _pair(self, pts: int, left: av.VideoFrame, right: av.VideoFrame) -> StereoFrame:
        tm = self.telemetry[pts]
        self.read_pairs += 1
        self.captured_at = tm.captured_at
        grey: list[U8] = [np.ascontiguousarray(f.to_ndarray(format="gray")) for f in (left, right)]
        t, offset = _frame_time(tm)
        return StereoFrame(tm.frame_no, grey[0], grey[1], t, t + offset, tm.gimbal)

    def close(self) -> None:
        for it in self._its.values():
            close = getattr(it, "close", None)
            if close is not None:
                close()
