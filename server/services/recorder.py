"""The recorder: the media pipeline's H.264 packets (no second encoder) -> fragmented MP4 segments per camera,
with the telemetry of every recorded frame, in its own thread (never the tracker's, never the event loop).

Modes: continuous; events (footage from `preroll_s` before a frame with detections, from a ring buffer of
packets that always starts on a keyframe, to `postroll_s` after the last one); off. A segment ends at the
first keyframe after `segment_s` (the recorder asks the encoder for one then), so every segment starts on a
keyframe. While the disk holding the data directory has less than `min_free_mb` free, or after a write failed
(the disk full, the database unable to store a segment's row), nothing is written and the status carries the
fault (tracking goes on); recording resumes once the disk has the floor plus a margin free again (a failed
write is retried with a back-off from 2 s to 60 s).
"""

from __future__ import annotations

import logging
import shutil
import threading
import time
from collections import OrderedDict, deque
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from sqlalchemy.exc import OperationalError
from sqlalchemy.orm import Session, sessionmaker

from server.services import segments
from server.services.faults import FailureLog, brief
from tmeye.media.encoder import CLOCK_HZ, EncodedFrame
from tmeye.media.fmp4 import SegmentMuxer
from tmeye.media.pipeline import CAMERAS, MediaPipeline
from tmeye.runtime import Runtime
from tmeye.runtime.publish import Subscription

log = logging.getLogger("tmeye.recording")
DISK_CHECK_S = 2.0
RETRY_MAX_S = 60.0
TELEMETRY_FLUSH_S = 1.0
KEY_LEAD_S = 0.02  # ask for the next segment's keyframe this long before the segment's length is reached


@dataclass(frozen=True)
class RecorderConfig:
    """mode: continuous, events or off; times in seconds; min_free_mb: the free-disk floor (MB)."""

    mode: str = "continuous"
    segment_s: float = 10.0
    preroll_s: float = 5.0
    postroll_s: float = 5.0
    min_free_mb: float = 1024.0


def segment_path(camera: str, captured_at: float) -> str:
    """recordings/YYYY-MM-DD/HH/{camera}/MM.SS.mp4 of a segment starting at `captured_at` (UTC)."""
    g = time.gmtime(captured_at)
    return f"recordings/{time.strftime('%Y-%m-%d', g)}/{g.tm_hour:02d}/{camera}/{g.tm_min:02d}.{g.tm_sec:02d}.mp4"


class CameraRecorder:
    """One camera's packets -> its open segment, or the pre-roll ring while nothing is being recorded."""

    def __init__(self, camera: str, owner: Recorder):
        self.camera, self.owner = camera, owner
        self.ring: deque[EncodedFrame] = deque()
        self.muxer: SegmentMuxer | None = None
        self.seg_id: int | None = None
        self.asked_key = False
        self.segments = self.frames = self.bytes = self.errors = 0

    def feed(self, ef: EncodedFrame, wanted: bool, kind: str) -> None:
        if self.muxer is not None and not wanted:
            self.close()
        if self.muxer is None:
            self._buffer(ef)
            if wanted:
                self._open_from_ring(kind)
            return
        elapsed = (ef.pts - self.muxer.start_pts) / CLOCK_HZ
        if ef.keyframe and (self.asked_key or elapsed >= self.owner.config.segment_s):
            self.close()  # the keyframe asked for (or a natural one past the length) starts the next segment
            self._buffer(ef)
            self._open_from_ring(kind)
            return
        if elapsed >= self.owner.config.segment_s - KEY_LEAD_S and not self.asked_key:
            self.owner.media.request_keyframe(self.camera)
            self.asked_key = True
        self._write(ef)

    def _buffer(self, ef: EncodedFrame) -> None:
        """Keep packets from the newest keyframe at least `preroll_s` old (a decodable pre-roll)."""
        if not self.ring and not ef.keyframe:
            self.owner.media.request_keyframe(self.camera)
            return
        self.ring.append(ef)
        horizon = ef.captured_at - self.owner.config.preroll_s
        keys = [i for i, p in enumerate(self.ring) if p.keyframe and p.captured_at <= horizon]
        for _ in range(keys[-1] if keys else 0):
            self.ring.popleft()

    def _open_from_ring(self, kind: str) -> None:
        if not self.ring:
            return
        first = self.ring.popleft()
        rel = self.owner.free_path(segment_path(self.camera, first.captured_at))
        try:
            self.seg_id = segments.open_row(self.owner.sessions, self.camera, kind, rel, first.captured_at,
                                            first.pts)
        except Exception as exc:
            self.errors += 1
            self.ring.clear()
            self.owner.failed(f"{self.camera}: storing the row of segment {rel} failed", exc)
            return
        try:
            self.muxer = SegmentMuxer(self.owner.data_dir / rel, first)
        except Exception as exc:
            self.errors += 1
            (self.owner.data_dir / rel).unlink(missing_ok=True)
            self.owner.unfinished.append(self.seg_id)  # its row goes once the database takes the change
            self.seg_id, self.muxer = None, None
            self.ring.clear()
            self.owner.failed(f"{self.camera}: cannot open segment {rel}", exc)
            return
        self.asked_key = False
        self.owner.resumed()
        self.owner.written(self.camera, first)
        while self.ring:
            self._write(self.ring.popleft())

    def _write(self, ef: EncodedFrame) -> None:
        assert self.muxer is not None
        if ef.keyframe and not self.owner.commit_telemetry():
            return  # the muxer would write the finished fragment now, but its frames' telemetry is not stored
        try:
            self.muxer.write(ef)
        except Exception as exc:
            self.errors += 1
            self.owner.failed(f"{self.camera}: writing frame {ef.frame_no} failed", exc)
            return
        self.owner.written(self.camera, ef)

    def close(self) -> None:
        mux, seg_id = self.muxer, self.seg_id
        self.muxer, self.seg_id = None, None
        if mux is None or seg_id is None:
            return
        self.owner.commit_telemetry()
        try:
            size = mux.close()
            segments.close_row(self.owner.sessions, seg_id, size=size, offsets=mux.offsets,
                               frame_nos=mux.frame_nos, keyframes=mux.keyframes)
        except Exception as exc:
            self.errors += 1
            self.owner.unfinished.append(seg_id)  # repaired from its file up to its last complete fragment
            self.owner.failed(f"{self.camera}: closing {mux.path.name} failed", exc)
            return
        self.segments += 1
        self.owner._retry_s = 0.0
        self.frames += len(mux.offsets)
        self.bytes += size


class Recorder:
    """Start after the media pipeline; stop before it (the open segments are closed and their rows completed)."""

    def __init__(self, media: MediaPipeline, runtime: Runtime, sessions: sessionmaker[Session], data_dir: Path,
                 config: RecorderConfig):
        self.media, self.runtime, self.sessions, self.data_dir = media, runtime, sessions, data_dir
        self.config = config
        self.cameras = {c: CameraRecorder(c, self) for c in CAMERAS}
        self.fault: str | None = None
        self._failures = FailureLog(log, (OSError, OperationalError), logging.ERROR)
        self.unfinished: list[int] = []  # segments whose close failed: repaired (or dropped) when possible
        self._retry_s = 0.0
        self._retry_at = 0.0
        self._retrying = False  # the fault stands until a segment opens again (no alarm chatter per retry)
        self.last_event: float | None = None
        self.telemetry_rows = self.telemetry_missing = 0
        self._telemetry: OrderedDict[int, dict[str, Any]] = OrderedDict()
        self._pending: dict[int, int] = {}  # frame_no -> pts of written frames whose telemetry is not stored yet
        self._stop = threading.Event()
        self._wake = threading.Event()
        self._thread: threading.Thread | None = None
        self._subs: dict[str, Subscription[EncodedFrame]] = {}
        self._tm_sub: Subscription[Any] | None = None

    def start(self) -> None:
        if self.config.mode == "off":
            return
        wake = self._wake.set
        self._tm_sub = self.runtime.hub.subscribe(maxsize=90, notify=wake, name="recorder")
        self._subs = {c: self.media.packets[c].subscribe(maxsize=300, notify=wake, name=f"recorder-{c}")
                      for c in CAMERAS}
        self.media.recorders += 1
        self._thread = threading.Thread(target=self._run, name="tmeye-recorder", daemon=True)
        self._thread.start()

    def stop(self, timeout: float = 5.0) -> None:
        self._stop.set()
        self._wake.set()
        if self._thread is not None:
            self._thread.join(timeout)
            self.media.recorders -= 1

    def status(self) -> dict[str, Any]:
        state = "off" if self.config.mode == "off" else "fault" if self.fault else \
            "recording" if any(c.muxer is not None for c in self.cameras.values()) else "idle"
        return {"mode": self.config.mode, "state": state, "fault": self.fault,
                "segments": sum(c.segments for c in self.cameras.values()),
                "frames": {n: c.frames for n, c in self.cameras.items()},
                "bytes": sum(c.bytes for c in self.cameras.values()),
                "errors": sum(c.errors for c in self.cameras.values()),
                "dropped_packets": sum(s.dropped for s in self._subs.values()),
                "telemetry_rows": self.telemetry_rows, "telemetry_missing": self.telemetry_missing}

    def free_path(self, rel: str) -> str:
        """`rel`, or with a -N suffix when a segment of the same second already exists."""
        n, out = 0, rel
        while (self.data_dir / out).exists():
            n += 1
            out = rel[:-4] + f"-{n}.mp4"
        return out

    def commit_telemetry(self) -> bool:
        """Store the telemetry of the frames written so far (before a fragment reaches the file); False when
        that failed (recording then stops)."""
        self._take_telemetry()
        try:
            self._flush_telemetry()
        except Exception as exc:
            if self.fault is None:
                self.failed("storing the telemetry of recorded frames failed", exc)
            return False
        return True

    def failed(self, what: str, exc: BaseException) -> None:
        """A write failed: stop recording (every open segment closed) until `_check_disk` retries."""
        first = self.fault is None
        self._retrying = False
        self.fault = f"{what}: {brief(exc)}"[:300] + ": recording stopped"
        if first:
            self._retry_s = min(RETRY_MAX_S, max(DISK_CHECK_S, 2 * self._retry_s))
            self._retry_at = time.monotonic() + self._retry_s
        # a full disk or a database that cannot write is a device fault (the recording alarm)
        self._failures.log(exc, "%s (retry in %.0f s)", self.fault, self._retry_s)
        for cam in self.cameras.values():
            if cam.muxer is not None:
                cam.close()

    def written(self, camera: str, ef: EncodedFrame) -> None:
        self._pending.setdefault(ef.frame_no, ef.pts)

    # --- the thread ----------------------------------------------------------------------------------
    def _run(self) -> None:
        next_disk = next_flush = 0.0
        try:
            while not self._stop.is_set():
                self._wake.wait(0.2)
                self._wake.clear()
                now = time.monotonic()
                try:
                    if now >= next_disk:
                        self._check_disk()
                        next_disk = now + DISK_CHECK_S
                    self._take_telemetry()
                    self._take_packets()
                    if now >= next_flush:
                        self.commit_telemetry()
                        next_flush = now + TELEMETRY_FLUSH_S
                except Exception as exc:  # recording stops and is retried; the thread goes on
                    self.failed("recording failed", exc)
        except Exception:
            log.exception("recorder stopped")
            self.fault = "recorder stopped after an error (see the log)"
        finally:
            self._take_telemetry()
            self._take_packets()
            for cam in self.cameras.values():
                cam.close()
            try:
                self._flush_telemetry(final=True)
            except Exception:
                log.exception("storing the last telemetry rows failed")
            for c, sub in self._subs.items():
                self.media.packets[c].unsubscribe(sub)
            if self._tm_sub is not None:
                self.runtime.hub.unsubscribe(self._tm_sub)

    def _take_telemetry(self) -> None:
        assert self._tm_sub is not None
        for ev in self._tm_sub.drain():
            self._telemetry[ev.frame_no] = ev.telemetry
            if ev.telemetry.get("detections"):
                self.last_event = ev.captured_at
        while len(self._telemetry) > 900:
            self._telemetry.popitem(last=False)

    def event(self, t: float) -> None:
        """Something worth recording happened at capture time t (Unix s), e.g. an alarm's activation: in
        events mode the footage from pre-roll before it to post-roll after it is kept (called from any thread)."""
        last = self.last_event
        self.last_event = t if last is None else max(last, t)

    def _wanted(self, t: float) -> bool:
        if self.fault and not self._retrying:
            return False
        if self.config.mode == "continuous":
            return True
        return self.last_event is not None and t <= self.last_event + self.config.postroll_s

    def _take_packets(self) -> None:
        kind = "continuous" if self.config.mode == "continuous" else "event"
        for c, sub in self._subs.items():
            for ef in sub.drain():
                self.cameras[c].feed(ef, self._wanted(ef.captured_at), kind)

    def _flush_telemetry(self, final: bool = False) -> None:
        rows, keep = [], {}
        for frame_no, pts in self._pending.items():
            tm = self._telemetry.get(frame_no)
            if tm is not None:
                rows.append({"pts": pts, "frame_no": frame_no, "captured_at": pts / CLOCK_HZ, "data": tm})
            elif not final and frame_no > max(self._telemetry, default=0):
                keep[frame_no] = pts  # its telemetry has not come yet
            else:
                self.telemetry_missing += 1
        self._pending = keep
        try:
            self.telemetry_rows += segments.save_telemetry(self.sessions, rows)
        except Exception:
            self.telemetry_missing += len(rows)
            raise

    def _check_disk(self) -> None:
        """Stop recording under the free-space floor; resume (after a failed write: at its retry time) once the
        floor plus a margin (5 % of it, at least 1 MB) is free; repair the segments whose close failed."""
        self._repair_unfinished()
        try:
            self.data_dir.mkdir(parents=True, exist_ok=True)
            free_mb = shutil.disk_usage(self.data_dir).free / 1e6
        except OSError as exc:
            self.fault, self._retrying = f"the data directory cannot be checked: {exc}: recording stopped", False
            return
        floor = self.config.min_free_mb
        if free_mb < floor:
            self._retrying = False
            if self.fault is None or "below the floor" not in self.fault:
                self.fault = f"free disk space {free_mb:.0f} MB is below the floor of {floor:.0f} MB: recording stopped"
                log.error("%s", self.fault)
            for cam in self.cameras.values():
                cam.close()
        elif self.fault is not None and free_mb >= floor + max(1.0, 0.05 * floor) and \
                time.monotonic() >= self._retry_at and not self.unfinished:
            if "below the floor" in self.fault:
                self.resumed()  # the space is back: nothing needs to be tried to know it
            else:
                self._retrying = True  # a failed write: the fault stands until a segment opens again

    def resumed(self) -> None:
        """A segment opened: a standing fault is over."""
        if self.fault is not None:
            log.warning("recording resumed after: %s", self.fault)
            self.fault, self._retrying = None, False

    def _repair_unfinished(self) -> None:
        while self.unfinished:
            try:
                segments.repair(self.sessions, self.data_dir, self.unfinished[0])
            except Exception as exc:
                log.warning("repairing segment %d failed (retried): %s", self.unfinished[0], str(exc).splitlines()[0])
                return
            self.unfinished.pop(0)
