"""Evidence locks (footage kept from retention until an admin unlocks it) and bookmarks, with the audit log."""

from __future__ import annotations

import time

from sqlalchemy import select
from sqlalchemy.orm import Session

from server.db.models import Alarm, Bookmark, EvidenceLock, Track, User
from server.services import audit
from server.services.errors import NotFound


def alarm_range(alarm: Alarm, preroll_s: float, postroll_s: float, now: float) -> tuple[float, float]:
    """The footage of an alarm (Unix s): from its activation less the pre-roll to its clear plus the post-roll,
    or to now while it is active."""
    end = alarm.cleared_at + postroll_s if alarm.cleared_at is not None else now
    return alarm.activated_at - preroll_s, max(end, alarm.activated_at)


def add_lock(db: Session, user: User, address: str, start: float | None, end: float | None, track_id: int | None,
             note: str, roll_s: tuple[float, float], alarm_id: int | None = None) -> EvidenceLock:
    """Lock start..end, a track's first to last sighting or an alarm's footage (`alarm_range`), the last two
    widened by roll_s = (pre-roll, post-roll) seconds."""
    if track_id is not None:
        tr = db.get(Track, track_id)
        if tr is None:
            raise NotFound(f"no track with id {track_id}")
        start, end = tr.first_seen - roll_s[0], tr.last_seen + roll_s[1]
    if alarm_id is not None:
        alarm = db.get(Alarm, alarm_id)
        if alarm is None:
            raise NotFound(f"no alarm with id {alarm_id}")
        start, end = alarm_range(alarm, roll_s[0], roll_s[1], time.time())
    assert start is not None and end is not None
    row = EvidenceLock(start=start, end=end, track_id=track_id, alarm_id=alarm_id, note=note, created_at=time.time(),
                       created_by=user.id)
    db.add(row)
    db.flush()
    audit.record(db, user, address, "evidence.lock", f"lock {row.id}",
                 {"start": start, "end": end, "track_id": track_id, "alarm_id": alarm_id, "note": note})
    db.commit()
    return row


def remove_lock(db: Session, user: User, address: str, lock_id: int) -> None:
    row = db.get(EvidenceLock, lock_id)
    if row is None:
        raise NotFound(f"no evidence lock with id {lock_id}")
    audit.record(db, user, address, "evidence.unlock", f"lock {lock_id}", {"start": row.start, "end": row.end})
    db.delete(row)
    db.commit()


def list_locks(db: Session, start: float | None, end: float | None) -> list[EvidenceLock]:
    q = select(EvidenceLock).order_by(EvidenceLock.start)
    if start is not None:
        q = q.where(EvidenceLock.end >= start)
    if end is not None:
        q = q.where(EvidenceLock.start <= end)
    return list(db.scalars(q))


def add_bookmark(db: Session, user: User, address: str, t: float, note: str) -> Bookmark:
    row = Bookmark(t=t, note=note, created_at=time.time(), created_by=user.id)
    db.add(row)
    db.flush()
    audit.record(db, user, address, "bookmark.add", f"bookmark {row.id}", {"t": t, "note": note})
    db.commit()
    return row


def remove_bookmark(db: Session, user: User, address: str, bookmark_id: int) -> None:
    row = db.get(Bookmark, bookmark_id)
    if row is None:
        raise NotFound(f"no bookmark with id {bookmark_id}")
    audit.record(db, user, address, "bookmark.delete", f"bookmark {bookmark_id}", {"t": row.t, "note": row.note})
    db.delete(row)
    db.commit()


def list_bookmarks(db: Session, start: float | None, end: float | None) -> list[Bookmark]:
    q = select(Bookmark).order_by(Bookmark.t)
    if start is not None:
        q = q.where(Bookmark.t >= start)
    if end is not None:
        q = q.where(Bookmark.t <= end)
    return list(db.scalars(q))
