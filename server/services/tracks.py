"""Tracks: `TrackBook` folds each frame's detections into per-track summaries and trajectory samples
(pure, no I/O); `TrackWriter` runs it on the runtime's published frames and commits in batches from a
thread (never per frame, never on the event loop); the queries serve /api/tracks."""

from __future__ import annotations

import asyncio
import logging
import math
import time
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from sqlalchemy import insert, select
from sqlalchemy.orm import Session, sessionmaker

from server.db.models import Track, TrackPoint
from server.services.errors import NotFound
from server.services.faults import FailureLog, brief
from tmeye.runtime import FrameEvent, Runtime

log = logging.getLogger("tmeye.tracks")

# a track's speed: the least-squares velocity of its positions over the last SPEED_WINDOW_S, once they span
# SPEED_MIN_SPAN_S. Differences of positions 50 ms apart gave walkers at 0.8-1.8 m/s peaks of 5.2-5.6 m/s
# (the endless scene, measured in the console's Tracks table): a range 1-σ of 0.1 m over 2 frames is 2 m/s
SPEED_WINDOW_S = 1.0
SPEED_MIN_SPAN_S = 0.5
# a track is written once it was detected in this many frames: the single frames of noise, a leaf or the
# edge of a light change (tracks of 1 to 4 detections and 0.05 m across in a minute of the endless scene)
# are not tracks an operator looks for (as an NVR's event needs a few frames)
MIN_DETECTIONS = 5


@dataclass
class TrackSummary:
    """A track as seen so far. Times Unix s; speed m/s; size m (median-free: the latest confirmed);
    recent: its positions (t, x, y, z) of the last SPEED_WINDOW_S."""

    generation: int
    track_no: int
    first_seen: float
    last_seen: float
    detections: int = 0
    peak_speed_mps: float = 0.0
    width_m: float | None = None
    height_m: float | None = None
    min_range_m: float | None = None
    recent: deque[tuple[float, float, float, float]] = field(default_factory=deque)
    last_sample_t: float = -math.inf
    pending: list[dict[str, float]] = field(default_factory=list)
    db_id: int | None = None
    dirty: bool = True


def fitted_speed(points: Sequence[tuple[float, float, float, float]]) -> float:
    """The speed (m/s) of the least-squares straight line through positions (t s, x, y, z m) against
    time: |v|, v = Σ (t - t̄)(p - p̄) / Σ (t - t̄)²; 0 with fewer than 2 points or no spread in time."""
    n = len(points)
    if n < 2:
        return 0.0
    tm = sum(p[0] for p in points) / n
    means = [sum(p[k] for p in points) / n for k in (1, 2, 3)]
    stt = sum((p[0] - tm) ** 2 for p in points)
    if stt <= 0.0:
        return 0.0
    v = [sum((p[0] - tm) * (p[k] - means[k - 1]) for p in points) / stt for k in (1, 2, 3)]
    return math.hypot(*v)


class TrackBook:
    """Per-track summaries from telemetry messages. `sample_hz`: trajectory samples per second kept."""

    def __init__(self, sample_hz: float):
        self.min_dt = 1.0 / sample_hz
        self.tracks: dict[tuple[int, int], TrackSummary] = {}

    def add(self, tm: dict[str, Any], generation: int = 0) -> None:
        """Fold in one frame's telemetry; `generation` tells pipelines apart (their track ids restart)."""
        t = float(tm["captured_at"])
        for d in tm.get("detections", ()):
            key = (generation, int(d["track_id"]))
            tr = self.tracks.get(key)
            if tr is None:
                tr = self.tracks[key] = TrackSummary(generation, d["track_id"], t, t)
            self._update(tr, d, t)

    def _update(self, tr: TrackSummary, d: dict[str, Any], t: float) -> None:
        tr.last_seen, tr.detections, tr.dirty = t, tr.detections + 1, True
        x, y, z = float(d["x"]), float(d["y"]), float(d["z"])
        tr.recent.append((t, x, y, z))
        while t - tr.recent[0][0] > SPEED_WINDOW_S:
            tr.recent.popleft()
        if d.get("size_m"):
            tr.width_m, tr.height_m = float(d["size_m"][0]), float(d["size_m"][1])
        tr.min_range_m = d["r"] if tr.min_range_m is None else min(tr.min_range_m, float(d["r"]))
        if t - tr.last_sample_t >= self.min_dt * 0.999:
            tr.last_sample_t = t
            if t - tr.recent[0][0] >= SPEED_MIN_SPAN_S:  # at the samples' rate: the peak is no different
                tr.peak_speed_mps = max(tr.peak_speed_mps, fitted_speed(tr.recent))
            tr.pending.append({"t": t, "x": x, "y": y, "z": z, "r": float(d["r"]),
                               "theta_deg": float(d["theta_deg"]), "phi_deg": float(d["phi_deg"])})

    def forget_before(self, t: float) -> None:
        """Drop summaries last seen before t that have nothing left to write (or never will: too short)."""
        for k in [k for k, tr in self.tracks.items()
                  if tr.last_seen < t and (not tr.dirty or tr.detections < MIN_DETECTIONS)]:
            del self.tracks[k]


def flush(sessions: sessionmaker[Session], run_id: str, book: TrackBook, replay_id: int | None = None) -> int:
    """Write every changed track of at least MIN_DETECTIONS detections and its new samples in one
    transaction (a shorter one waits, its samples kept); returns the samples written. `replay_id`: the
    tracks are a replay's (None: the live runtime's)."""
    n = 0
    written = [tr for tr in book.tracks.values() if tr.dirty and tr.detections >= MIN_DETECTIONS]
    with sessions() as db, db.begin():
        for tr in written:
            row = db.get(Track, tr.db_id) if tr.db_id is not None else None
            if row is None:
                row = Track(run_id=f"{run_id}.{tr.generation}", track_no=tr.track_no, first_seen=tr.first_seen,
                            last_seen=tr.last_seen, detections=0, peak_speed_mps=0.0, replay_id=replay_id)
                db.add(row)
            row.last_seen, row.detections, row.peak_speed_mps = tr.last_seen, tr.detections, tr.peak_speed_mps
            row.width_m, row.height_m, row.min_range_m = tr.width_m, tr.height_m, tr.min_range_m
            db.flush()
            tr.db_id = row.id
            if tr.pending:  # one executemany (Core): the ORM's per-object work would hold the GIL
                db.execute(insert(TrackPoint), [{"track_id": row.id, **p} for p in tr.pending])
            n += len(tr.pending)
    for tr in written:  # committed: only now forget what was written
        tr.pending.clear()
        tr.dirty = False
    return n


class TrackWriter:
    """The asyncio task that feeds a TrackBook from the runtime and flushes it every `flush_s`."""

    def __init__(self, runtime: Runtime, sessions: sessionmaker[Session], sample_hz: float, flush_s: float):
        self.runtime, self.sessions, self.flush_s = runtime, sessions, flush_s
        self.book = TrackBook(sample_hz)
        self.run_id = time.strftime("%Y%m%dT%H%M%S", time.gmtime()) + f"-{int(time.time() * 1000) % 1000:03d}"
        self.written = 0
        self.errors = 0
        self._failures = FailureLog(log)

    async def run(self) -> None:
        # no wake-up per frame: every flush_s the frames queued meanwhile are folded in and written at once
        # (the queue holds 20 s of frames at 30 fps; beyond that the oldest are dropped and counted)
        sub = self.runtime.hub.subscribe(maxsize=600, name="track-writer")
        try:
            while True:
                await asyncio.sleep(self.flush_s)
                self._take(sub.drain())
                await self._flush()
                if sub.closed and not len(sub):
                    return
        finally:
            self.runtime.hub.unsubscribe(sub)
            self._take(sub.drain())
            await asyncio.shield(self._flush())

    def _take(self, events: list[FrameEvent]) -> None:
        for ev in events:
            self.book.add(ev.telemetry, ev.generation)

    async def _flush(self) -> None:
        try:
            self.written += await asyncio.to_thread(flush, self.sessions, self.run_id, self.book)
            self.book.forget_before(time.time() - 60.0)
        except Exception as exc:  # kept in memory, retried at the next flush
            self.errors += 1
            self._failures.log(exc, "writing tracks failed (%d times; kept in memory, retried at the next flush): %s",
                               self.errors, brief(exc))


def list_tracks(db: Session, start: float | None, end: float | None, limit: int,
                replay_id: int | None = None) -> list[Track]:
    """The live tracks (replay_id None) or one replay's, overlapping start..end, newest first."""
    q = (select(Track).where(Track.replay_id.is_(None) if replay_id is None else Track.replay_id == replay_id)
         .order_by(Track.first_seen.desc()).limit(limit))
    if start is not None:
        q = q.where(Track.last_seen >= start)
    if end is not None:
        q = q.where(Track.first_seen <= end)
    return list(db.scalars(q))


def get_track(db: Session, track_id: int) -> tuple[Track, list[TrackPoint]]:
    tr = db.get(Track, track_id)
    if tr is None:
        raise NotFound(f"no track with id {track_id}")
    pts = list(db.scalars(select(TrackPoint).where(TrackPoint.track_id == track_id).order_by(TrackPoint.t)))
    return tr, pts
