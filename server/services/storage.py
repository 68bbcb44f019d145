"""Retention applied: the engine's decisions (server.services.retention) carried out on files and rows,
from a thread every `retention_interval_s`; the telemetry of footage no segment holds any longer goes too."""

from __future__ import annotations

import asyncio
import logging
import time
from pathlib import Path

from sqlalchemy import delete, exists, select
from sqlalchemy.orm import Session, sessionmaker

from server.db.models import EvidenceLock, RecordedFrame, Segment
from server.services.faults import FailureLog, brief
from server.services.retention import Policy, SegmentInfo, to_delete

log = logging.getLogger("tmeye.retention")


def apply_retention(sessions: sessionmaker[Session], data_dir: Path, policy: Policy,
                    now: float | None = None) -> list[int]:
    """Delete what the policy says; returns the ids of the segments deleted."""
    with sessions() as db:
        rows = db.execute(select(Segment.id, Segment.kind, Segment.start, Segment.end, Segment.bytes,
                                 Segment.status)).all()
        locks = [(lo, hi) for lo, hi in db.execute(select(EvidenceLock.start, EvidenceLock.end)).all()]
    infos = [SegmentInfo(i, k, s, e if st != "open" else None, b) for i, k, s, e, b, st in rows]
    ids = to_delete(infos, locks, policy, time.time() if now is None else now)
    if not ids:
        return []
    with sessions() as db, db.begin():
        gone = list(db.scalars(select(Segment).where(Segment.id.in_(ids))))
        paths = [data_dir / seg.path for seg in gone]
        for seg in gone:
            db.delete(seg)
        db.flush()
        for seg in gone:
            held = exists().where(Segment.start <= RecordedFrame.captured_at,
                                  Segment.end >= RecordedFrame.captured_at)
            db.execute(delete(RecordedFrame).where(RecordedFrame.captured_at >= seg.start,
                                                   RecordedFrame.captured_at <= (seg.end or seg.start), ~held))
    # the rows go first: no reader ever sees a row whose file is gone; a file left by a crash here is
    # removed by the start-up reconciliation (files without rows)
    for path in paths:
        path.unlink(missing_ok=True)
    log.info("retention deleted %d segments", len(ids))
    return ids


class RetentionTask:
    """The asyncio task that runs retention in a thread every `interval_s`."""

    def __init__(self, sessions: sessionmaker[Session], data_dir: Path, policy: Policy, interval_s: float):
        self.sessions, self.data_dir, self.policy, self.interval_s = sessions, data_dir, policy, interval_s
        self.deleted = 0
        self.errors = 0
        self.last_run: float | None = None
        self._failures = FailureLog(log)

    async def run(self) -> None:
        while True:
            try:
                self.deleted += len(await asyncio.to_thread(apply_retention, self.sessions, self.data_dir,
                                                            self.policy))
            except Exception as exc:  # tried again at the next interval
                self.errors += 1
                self._failures.log(exc, "retention failed (tried again at the next interval): %s", brief(exc))
            self.last_run = time.time()
            await asyncio.sleep(self.interval_s)
