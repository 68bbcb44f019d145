"""Segment rows and recorded telemetry: the recorder's writes (a row when a segment opens, completed when it
closes, telemetry in batches), the start-up reconciliation of rows and files after a crash, and the queries
of the playback API. Paths in rows are relative to the data directory."""

from __future__ import annotations

import logging
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from sqlalchemy import delete, select
from sqlalchemy.dialects.sqlite import insert as sqlite_insert
from sqlalchemy.orm import Session, sessionmaker

from server.db.models import RecordedFrame, Segment
from server.services.errors import NotFound
from tmeye.media.encoder import CLOCK_HZ
from tmeye.media.fmp4 import index_file, truncate_to_fragments

log = logging.getLogger("tmeye.recording")


def open_row(sessions: sessionmaker[Session], camera: str, kind: str, path: str, start: float, start_pts: int) -> int:
    with sessions() as db, db.begin():
        row = Segment(camera=camera, kind=kind, path=path, status="open", start=start, end=None, start_pts=start_pts,
                      frames=0, bytes=0, keyframes=[], frame_offsets=[], frame_nos=[])
        db.add(row)
        db.flush()
        return row.id


def close_row(sessions: sessionmaker[Session], seg_id: int, *, size: int, offsets: list[int], frame_nos: list[int],
              keyframes: list[int], status: str = "closed") -> None:
    """Complete a segment's row: end, frame count, bytes, keyframe times (s), frame offsets (ticks)."""
    with sessions() as db, db.begin():
        row = db.get(Segment, seg_id)
        if row is None:
            return
        row.status, row.bytes, row.frames = status, size, len(offsets)
        row.end = (row.start_pts + offsets[-1]) / CLOCK_HZ if offsets else row.start
        row.frame_offsets, row.frame_nos = offsets, frame_nos
        row.keyframes = [round(k / CLOCK_HZ, 6) for k in keyframes]


def delete_row(sessions: sessionmaker[Session], seg_id: int) -> None:
    with sessions() as db, db.begin():
        db.execute(delete(Segment).where(Segment.id == seg_id))


def save_telemetry(sessions: sessionmaker[Session], rows: Iterable[dict[str, Any]]) -> int:
    """Insert recorded frames' telemetry ({pts, frame_no, captured_at, data}); a pts already stored is kept."""
    batch = list(rows)
    if batch:
        with sessions() as db, db.begin():
            db.execute(sqlite_insert(RecordedFrame).on_conflict_do_nothing(index_elements=["pts"]), batch)
    return len(batch)


def reconcile(sessions: sessionmaker[Session], data_dir: Path) -> dict[str, int]:
    """After a crash: every open row's file is cut after its last complete fragment and its row corrected
    (status cut) or, with nothing usable, both go; rows whose file is missing go; recording files that no
    row names are deleted. Returns the counts."""
    out = {"cut": 0, "dropped": 0, "missing": 0, "orphans": 0}
    with sessions() as db, db.begin():
        rows = list(db.scalars(select(Segment)))
        known = {r.path for r in rows}
        for row in rows:
            f = data_dir / row.path
            if not f.exists():
                log.warning("segment %d: file %s is missing; row removed", row.id, row.path)
                db.delete(row)
                out["missing"] += 1
            elif row.status == "open":
                out[_repair(db, row, f)] += 1
    rec = data_dir / "recordings"
    for f in rec.rglob("*.mp4") if rec.is_dir() else ():
        if str(f.relative_to(data_dir)) not in known:
            log.warning("recording file %s has no row; deleted", f)
            f.unlink(missing_ok=True)
            out["orphans"] += 1
    return out


def repair(sessions: sessionmaker[Session], data_dir: Path, seg_id: int) -> str:
    """One segment whose writing failed: its file cut after the last complete fragment and its row corrected,
    or both removed (nothing usable, or no file). Returns cut, dropped or missing."""
    with sessions() as db, db.begin():
        row = db.get(Segment, seg_id)
        if row is None:
            return "missing"
        f = data_dir / row.path
        if not f.exists():
            db.delete(row)
            return "missing"
        return _repair(db, row, f)


def _repair(db: Session, row: Segment, f: Path) -> str:
    size = truncate_to_fragments(f)
    idx = index_file(f) if size else None
    if idx is None or not idx.pts:
        log.warning("segment %d (%s): nothing complete was written; removed", row.id, row.path)
        f.unlink(missing_ok=True)
        db.delete(row)
        return "dropped"
    nos = dict(db.execute(select(RecordedFrame.pts, RecordedFrame.frame_no)
                          .where(RecordedFrame.pts.between(row.start_pts, row.start_pts + idx.pts[-1]))).all())
    row.status, row.bytes, row.frames = "cut", size, len(idx.pts)
    row.end = (row.start_pts + idx.pts[-1]) / CLOCK_HZ
    row.frame_offsets = idx.pts
    row.frame_nos = [int(nos.get(row.start_pts + p, -1)) for p in idx.pts]
    row.keyframes = [round(k / CLOCK_HZ, 6) for k in idx.keyframes]
    log.warning("segment %d (%s): cut (a crash or a failed write); kept %d frames up to its last complete fragment",
                row.id, row.path, row.frames)
    return "cut"


def list_segments(db: Session, camera: str | None, start: float | None, end: float | None,
                  limit: int) -> list[Segment]:
    q = select(Segment).order_by(Segment.start).limit(limit)
    if camera is not None:
        q = q.where(Segment.camera == camera)
    if start is not None:
        q = q.where((Segment.end >= start) | (Segment.end.is_(None)))
    if end is not None:
        q = q.where(Segment.start <= end)
    return list(db.scalars(q))


def get_segment(db: Session, seg_id: int) -> Segment:
    row = db.get(Segment, seg_id)
    if row is None:
        raise NotFound(f"no recording segment with id {seg_id}")
    return row


def segment_at(db: Session, camera: str, t: float) -> Segment | None:
    """The finished segment of `camera` that started last at or before t."""
    q = (select(Segment).where(Segment.camera == camera, Segment.start <= t, Segment.status != "open")
         .order_by(Segment.start.desc()).limit(1))
    return db.scalars(q).first()


def telemetry_range(db: Session, start: float, end: float, limit: int) -> list[dict[str, Any]]:
    q = (select(RecordedFrame.data).where(RecordedFrame.captured_at >= start, RecordedFrame.captured_at <= end)
         .order_by(RecordedFrame.pts).limit(limit))
    return list(db.scalars(q))
